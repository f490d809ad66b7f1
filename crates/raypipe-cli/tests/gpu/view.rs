//! `raypipe view` in a virtual X display (Xvfb): its scripted frames are `raypipe render`'s image,
//! one sample per pixel or many (progressive anti-aliasing against `render --spp`), the window
//! itself shows that image (the surface path, not only the readback), the scripted orbit and a
//! moving scene change the frames, and a mode that cannot serve the scene is refused.

use crate::common::harness::Test;
use crate::common::test_dir;
use crate::common::{raypipe, render_on_cpu};
use crate::io;
use raypipe::gpu::GpuContext;
use raypipe::image::diff::{Tolerance, compare};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicU32, Ordering};

const XVFB_SCREEN: &str = "-screen 0 1024x768x24";

/// `xvfb-run` on a display number of this test process's own. `xvfb-run -a` takes the first number
/// without a lock file, so two window tests starting at once could take the same one, and the
/// second's program then fails to connect.
fn xvfb_run() -> Command {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    // A block of numbers per process; numbers another server holds are skipped.
    let base = 200 + (std::process::id() % 500) * 64;
    let display = loop {
        let n = base + NEXT.fetch_add(1, Ordering::Relaxed) % 64;
        if !Path::new(&format!("/tmp/.X{n}-lock")).exists() {
            break n;
        }
    };
    let mut command = Command::new("xvfb-run");
    command.args(["-n", &display.to_string(), "-s", XVFB_SCREEN]);
    command
}

/// What an X client says when the virtual server it was handed refuses it: seen once in CI among
/// hundreds of runs, a server that had not come up. Such a run is tried again on another display.
const NO_SERVER: &str = "Failed to open connection to X server";

/// `command` (a program and its arguments) in a fresh virtual display, run again (three tries in
/// all) where the server refused the connection: on its standard error or, for a script that sends
/// the viewer's elsewhere, in `log`.
fn xvfb_output(command: &[&str], log: Option<&Path>) -> Output {
    for attempt in 1.. {
        if let Some(log) = log {
            let _ = std::fs::remove_file(log);
        }
        let output = xvfb_run().args(command).output().unwrap();
        let logged = log.map(|l| std::fs::read_to_string(l).unwrap_or_default());
        let refused = String::from_utf8_lossy(&output.stderr).contains(NO_SERVER)
            || logged.is_some_and(|l| l.contains(NO_SERVER));
        if !refused || attempt == 3 {
            return output;
        }
        eprintln!("the virtual X server refused the connection (try {attempt}); again on another display");
    }
    unreachable!("the loop returns by the third try")
}

/// `raypipe ARGS` in a fresh virtual display.
fn in_xvfb(args: &[&str]) -> Output {
    xvfb_output(&[&[env!("CARGO_BIN_EXE_raypipe")], args].concat(), None)
}

fn succeeded(output: &Output, what: &str) {
    assert!(
        output.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// The scripted viewer's last frame of `scene` at 160x120; one sample per pixel unless `extra`
/// says otherwise.
fn viewed(dir: &Path, scene: &str, extra: &[&str], frames: u32) -> PathBuf {
    let shot = dir.join(format!("view-{}-{frames}.png", scene.replace([':', '/'], "-")));
    let frames = frames.to_string();
    let mut args = vec!["view", scene, "--width", "160", "--height", "120", "--frames", &frames];
    if !extra.contains(&"--spp") {
        args.extend(["--spp", "1"]);
    }
    args.extend_from_slice(extra);
    args.extend(["--screenshot", shot.to_str().unwrap()]);
    succeeded(&in_xvfb(&args), &format!("raypipe {}", args.join(" ")));
    shot
}

fn rendered(dir: &Path, scene: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(format!("render-{}.png", scene.replace([':', '/'], "-")));
    let mut args = vec!["render", scene, "--width", "160", "--height", "120", "--device", "gpu"];
    // One sample, as `viewed` gathers (a glTF file's render takes more by default).
    if !extra.contains(&"--spp") {
        args.extend(["--spp", "1"]);
    }
    args.extend_from_slice(extra);
    args.extend(["-o", out.to_str().unwrap()]);
    succeeded(&raypipe(&args), "raypipe render");
    out
}

fn matches(a: &Path, b: &Path) -> Result<(), String> {
    let stats = compare(&io::read(a).unwrap(), &io::read(b).unwrap()).map_err(|e| e.to_string())?;
    Tolerance::COLOR.check(&stats).map_err(|e| e.to_string())
}

fn scripted_frames_are_the_render(_: &GpuContext) {
    let dir = test_dir("view-scripted");
    // The viewer through the compute pipeline shows render's frame from the fragment pipeline.
    for (scene, viewer_flags, render_flags) in [
        ("whitted", &[][..], &[][..]),
        ("random:2000", &["--accel", "stack"][..], &["--accel", "stack"][..]),
        ("whitted", &["--pipeline", "compute"][..], &[][..]),
    ] {
        let shot = viewed(&dir, scene, viewer_flags, 3);
        let render = rendered(&dir, scene, render_flags);
        matches(&shot, &render).unwrap_or_else(|e| panic!("{scene}: the viewer's frame is not render's: {e}"));
    }
}

/// A glTF scene (the shared BoxTextured sample, its texture sampled in the shader) shows in the
/// window as `render` draws it, in storage and in texture memory.
fn a_gltf_scene_views_as_it_renders(_: &GpuContext, models: &Path) {
    let dir = test_dir("view-gltf");
    let scene = models.join("gltf/BoxTextured.gltf");
    let scene = scene.to_str().unwrap();
    // Kept by a name of its own: render's files are named by the scene alone.
    let render = dir.join("render-plain.png");
    std::fs::rename(rendered(&dir, scene, &[]), &render).unwrap();
    for memory in ["storage", "texture"] {
        let shot = viewed(&dir, scene, &["--memory", memory], 3);
        matches(&shot, &render).unwrap_or_else(|e| panic!("BoxTextured in {memory} memory: {e}"));
    }
    // Exposure and tone map reach the viewer's screenshots as they reach render's PNG.
    let toned = ["--tonemap", "aces", "--exposure", "1"];
    let render_toned = dir.join("render-toned.png");
    std::fs::rename(rendered(&dir, scene, &toned), &render_toned).unwrap();
    let shot = viewed(&dir, scene, &toned, 3);
    matches(&shot, &render_toned).unwrap_or_else(|e| panic!("BoxTextured with ACES at +1 EV: {e}"));
    assert!(
        matches(&shot, &render).is_err(),
        "the tone map and exposure changed nothing"
    );
}

/// A still frame gathers one sample per frame up to --spp, then stays: twelve frames with
/// `--spp 8` are `render --spp 8`, not its one-sample image.
fn still_frames_gather_render_spp(_: &GpuContext) {
    let dir = test_dir("view-samples");
    let shot = viewed(&dir, "whitted", &["--spp", "8"], 12);
    let render = rendered(&dir, "whitted", &["--spp", "8"]);
    matches(&shot, &render).unwrap_or_else(|e| panic!("eight samples in the viewer are not render's: {e}"));
    let aliased = dir.join("aliased.png");
    std::fs::rename(rendered(&dir, "whitted", &[]), &aliased).unwrap();
    assert!(
        matches(&shot, &aliased).is_err(),
        "the viewer's frame did not gather samples"
    );
}

/// The X screen, captured while the viewer draws: the window at the screen's corner shows the frame.
fn the_window_shows_the_frame(_: &GpuContext) {
    let dir = test_dir("view-window");
    let expected = rendered(&dir, "whitted", &[]);
    let (root, crop) = (dir.join("root.png"), dir.join("window.png"));
    // Capture until the window has drawn (the first frame may compile shaders for a while).
    let script = format!(
        "'{raypipe}' view whitted --width 160 --height 120 --spp 1 --frames 100000000 & pid=$!
         for i in $(seq 120); do
           sleep 1
           import -window root '{root}' && convert '{root}' -crop 160x120+0+0 +repage '{crop}' \
             && '{raypipe}' diff '{crop}' '{expected}' --threshold 0.01 > /dev/null && break
         done
         kill $pid",
        raypipe = env!("CARGO_BIN_EXE_raypipe"),
        root = root.display(),
        crop = crop.display(),
        expected = expected.display(),
    );
    let output = xvfb_output(&["sh", "-c", &script], None);
    assert!(crop.exists(), "no capture: {}", String::from_utf8_lossy(&output.stderr));
    matches(&crop, &expected).unwrap_or_else(|e| panic!("the window does not show the frame: {e}"));
}

fn orbit_and_motion_change_the_frames(_: &GpuContext) {
    let dir = test_dir("view-motion");
    let still = viewed(&dir, "whitted", &[], 3);
    let turned = viewed(&dir, "whitted", &["--orbit", "15"], 4);
    assert!(matches(&still, &turned).is_err(), "--orbit left the image as it was");
    let first = viewed(&dir, "bounce:800", &[], 1);
    let later = viewed(&dir, "bounce:800", &[], 6);
    assert!(matches(&first, &later).is_err(), "bounce:800 did not move");
    // The same frame of a moving scene, twice: rebuilt the same way both times.
    let again = dir.join("again.png");
    std::fs::rename(&later, &again).unwrap();
    let later = viewed(&dir, "bounce:800", &[], 6);
    matches(&later, &again).unwrap();
}

/// An animated sample (the shared RiggedSimple) plays in the window: its frames change; held at a
/// time (`--paused`) they are `render --time` of that time, in storage memory (skinned on the GPU)
/// and in texture memory (on the CPU).
fn an_animated_sample_plays_and_holds_its_time(_: &GpuContext, models: &Path) {
    let dir = test_dir("view-animated");
    let scene = models.join("gltf/RiggedSimple.gltf");
    let scene = scene.to_str().unwrap();
    let first = viewed(&dir, scene, &[], 1);
    let later = viewed(&dir, scene, &[], 12);
    assert!(matches(&first, &later).is_err(), "RiggedSimple did not move");
    let render = rendered(&dir, scene, &["--time", "1.25"]);
    for memory in ["storage", "texture"] {
        let held = viewed(&dir, scene, &["--time", "1.25", "--paused", "--memory", memory], 4);
        matches(&held, &render).unwrap_or_else(|e| panic!("RiggedSimple held at 1.25 s in {memory} memory: {e}"));
    }
}

fn a_mode_that_cannot_serve_the_scene_is_one_line(_: &GpuContext) {
    let output = in_xvfb(&["view", "sphere-8k", "--memory", "uniform", "--frames", "1"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("too big for uniform memory") && !stderr.contains("panicked"),
        "{stderr}"
    );
}

/// A moving scene in texture memory (its BVH rebuilt on the CPU every frame) shows the frames of
/// storage memory (rebuilt on the GPU).
fn a_moving_scene_in_texture_memory_is_the_storage_one(_: &GpuContext) {
    let dir = test_dir("view-texture-motion");
    let storage = viewed(&dir, "bounce:800", &[], 5);
    let moved = dir.join("storage.png");
    std::fs::rename(&storage, &moved).unwrap();
    let texture = viewed(&dir, "bounce:800", &["--memory", "texture"], 5);
    matches(&texture, &moved).unwrap();
}

/// Keys and a drag through the X server (xdotool): `B` switches the acceleration (from the threaded
/// walk to the next, the wide walk) and the image stays, a drag orbits and the image changes; `P`
/// saves each state.
fn synthetic_input_switches_and_orbits(_ctx: &GpuContext) {
    let dir = test_dir("view-input");
    let expected = rendered(&dir, "whitted", &[]);
    // A viewer that could not open its window (a server that refused it) ends the script at once,
    // for the try on another display, rather than after the waits.
    let script = format!(
        "cd '{dir}'
         '{raypipe}' view whitted --width 160 --height 120 --spp 1 2> view.log & pid=$!
         for i in $(seq 120); do W=$(xdotool search --name raypipe | head -1); [ -n \"$W\" ] && break; kill -0 $pid || exit 1; sleep 1; done
         [ -n \"$W\" ] || exit 1
         xdotool windowfocus --sync $W
         shot() {{ xdotool key p; for i in $(seq 120); do [ -f $1 ] && break; kill -0 $pid || exit 1; sleep 0.5; done; }}
         xdotool key h
         shot raypipe-001.png
         xdotool key b
         shot raypipe-002.png
         xdotool mousemove --window $W 80 60 mousedown 1 mousemove --window $W 110 60 mousemove --window $W 140 60 mouseup 1
         sleep 1
         shot raypipe-003.png
         kill $pid",
        dir = dir.display(),
        raypipe = env!("CARGO_BIN_EXE_raypipe"),
    );
    let output = xvfb_output(&["sh", "-c", &script], Some(&dir.join("view.log")));
    let log = std::fs::read_to_string(dir.join("view.log")).unwrap_or_default();
    let shot = |n: u32| dir.join(format!("raypipe-{n:03}.png"));
    assert!(
        shot(3).exists(),
        "screenshots missing: {log} {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let next = "wide";
    assert!(
        log.contains(&format!("acceleration {next} ")),
        "B did not switch to {next}: {log}"
    );
    matches(&shot(1), &expected).unwrap();
    matches(&shot(2), &expected).unwrap_or_else(|e| panic!("{next}'s image is not the threaded walk's: {e}"));
    assert!(matches(&shot(3), &expected).is_err(), "the drag did not orbit");
}

/// Asks an X window to close, as a window manager's close button does: WM_DELETE_WINDOW through
/// libX11 (xdotool's windowclose destroys the window instead, which no user does).
const CLOSE_WINDOW: &str = r#"
import ctypes, sys
x = ctypes.cdll.LoadLibrary("libX11.so.6")
x.XOpenDisplay.restype = ctypes.c_void_p
x.XOpenDisplay.argtypes = [ctypes.c_char_p]
x.XFlush.argtypes = [ctypes.c_void_p]
x.XInternAtom.restype = ctypes.c_ulong
x.XInternAtom.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int]
class ClientMessage(ctypes.Structure):
    _fields_ = [("type", ctypes.c_int), ("serial", ctypes.c_ulong), ("send_event", ctypes.c_int),
                ("display", ctypes.c_void_p), ("window", ctypes.c_ulong), ("message_type", ctypes.c_ulong),
                ("format", ctypes.c_int), ("data", ctypes.c_long * 5)]
class Event(ctypes.Union):
    _fields_ = [("xclient", ClientMessage), ("pad", ctypes.c_long * 24)]
x.XSendEvent.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int, ctypes.c_long, ctypes.POINTER(Event)]
display = x.XOpenDisplay(None)
window = int(sys.argv[1])
event = Event()
event.xclient.type = 33
event.xclient.window = window
event.xclient.message_type = x.XInternAtom(display, b"WM_PROTOCOLS", 0)
event.xclient.format = 32
event.xclient.data[0] = x.XInternAtom(display, b"WM_DELETE_WINDOW", 0)
x.XSendEvent(display, window, 0, 0, ctypes.byref(event))
x.XFlush(display)
"#;

/// Window life under Xvfb: hidden and shown again (unmapped and mapped, which is what minimizing
/// does to an X window), then resized, the viewer still draws, now at the new size and with the
/// camera's aspect following it; asked to close, it exits 0.
fn the_window_survives_hiding_resizing_and_closes_cleanly(_: &GpuContext) {
    let dir = test_dir("view-window-life");
    let close = dir.join("close.py");
    std::fs::write(&close, CLOSE_WINDOW).unwrap();
    let script = format!(
        "cd '{dir}'
         '{raypipe}' view whitted --width 160 --height 120 --spp 1 2> view.log & pid=$!
         for i in $(seq 120); do W=$(xdotool search --name raypipe | head -1); [ -n \"$W\" ] && break; sleep 1; done
         sleep 2
         xdotool windowunmap --sync $W
         sleep 2
         xdotool windowmap --sync $W
         xdotool windowsize --sync $W 200 150
         sleep 2
         xdotool windowfocus --sync $W
         xdotool key p
         for i in $(seq 120); do [ -f raypipe-001.png ] && break; sleep 0.5; done
         python3 '{close}' $W
         # Bounded: a viewer that ignores the request is killed, and the test fails instead of hanging.
         for i in $(seq 120); do kill -0 $pid 2>/dev/null || break; sleep 0.5; done
         kill $pid 2>/dev/null
         wait $pid
         echo exit=$?",
        dir = dir.display(),
        raypipe = env!("CARGO_BIN_EXE_raypipe"),
        close = close.display(),
    );
    let output = xvfb_output(&["sh", "-c", &script], Some(&dir.join("view.log")));
    let stdout = String::from_utf8_lossy(&output.stdout);
    let log = std::fs::read_to_string(dir.join("view.log")).unwrap_or_default();
    assert!(stdout.contains("exit=0"), "closing did not exit 0: {stdout} {log}");
    let shot = dir.join("raypipe-001.png");
    let image = io::read(&shot).unwrap_or_else(|e| panic!("no screenshot after hiding and resizing: {e} {log}"));
    assert_eq!(
        (image.width, image.height),
        (200, 150),
        "the frame did not follow the window"
    );
    let out = dir.join("render-200x150.png");
    let args = [
        "render", "whitted", "--width", "200", "--height", "150", "--device", "gpu",
    ];
    succeeded(
        &raypipe(&[&args[..], &["-o", out.to_str().unwrap()]].concat()),
        "raypipe render",
    );
    matches(&shot, &out).unwrap_or_else(|e| panic!("the resized window's frame is not render's: {e}"));
}

/// The scripted viewer's last frame of whitted after `file` was dropped on it, and its output.
fn after_dropping(dir: &Path, file: &Path, shot: &str) -> (PathBuf, Output) {
    let shot = dir.join(shot);
    let output = in_xvfb(&[
        "view",
        "whitted",
        "--width",
        "160",
        "--height",
        "120",
        "--frames",
        "3",
        "--spp",
        "1",
        "--drop",
        file.to_str().unwrap(),
        "--screenshot",
        shot.to_str().unwrap(),
    ]);
    succeeded(&output, &format!("dropping {}", file.display()));
    (shot, output)
}

/// A dropped scene replaces the current one, a dropped environment lights it; a broken file shows
/// its error and the scene stays.
fn dropped_files_load_or_leave_the_scene(_: &GpuContext) {
    let dir = test_dir("view-drop");
    let broken = dir.join("broken.off");
    std::fs::write(&broken, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").unwrap();
    let (kept, output) = after_dropping(&dir, &broken, "kept.png");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("broken.off:6: face 0: vertex index 7 out of range"),
        "{stderr}"
    );
    matches(&kept, &rendered(&dir, "whitted", &[])).unwrap();
    let scene = dir.join("one.toml");
    std::fs::write(
        &scene,
        "[[light]]\nposition = [2, 4, -3]\n[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\n",
    )
    .unwrap();
    let (dropped, _) = after_dropping(&dir, &scene, "dropped.png");
    matches(&dropped, &rendered(&dir, scene.to_str().unwrap(), &[])).unwrap();

    // An environment lights the scene as `render --environment` does; one that is not 2:1 shows
    // its error and the scene stays as it was.
    let environment = dir.join("sky.exr");
    render_on_cpu("random:40:3", &environment, 64, 32);
    let (lit, _) = after_dropping(&dir, &environment, "lit.png");
    let with_environment = rendered(&dir, "whitted", &["--environment", environment.to_str().unwrap()]);
    matches(&lit, &with_environment).unwrap();
    assert!(
        matches(&lit, &rendered(&dir, "whitted", &[])).is_err(),
        "the environment did not show"
    );
    let square = dir.join("square.exr");
    render_on_cpu("whitted", &square, 32, 32);
    let (kept, output) = after_dropping(&dir, &square, "kept-environment.png");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("square.exr: 32x32: an equirectangular environment"),
        "{stderr}"
    );
    matches(&kept, &rendered(&dir, "whitted", &[])).unwrap();
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        gpu_window scripted_frames_are_the_render,
        gpu_window_models a_gltf_scene_views_as_it_renders,
        gpu_window still_frames_gather_render_spp,
        gpu_window the_window_shows_the_frame,
        gpu_window orbit_and_motion_change_the_frames,
        gpu_window_models an_animated_sample_plays_and_holds_its_time,
        gpu_window a_mode_that_cannot_serve_the_scene_is_one_line,
        gpu_window synthetic_input_switches_and_orbits,
        gpu_window the_window_survives_hiding_resizing_and_closes_cleanly,
        gpu_window dropped_files_load_or_leave_the_scene,
        gpu_window a_moving_scene_in_texture_memory_is_the_storage_one,
    ]
}
