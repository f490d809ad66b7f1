//! The panel: what runs, how fast, and the switches, in an egui window over the frame.

use crate::Modes;
use raypipe::Choice;
use raypipe::modes::Aov;
use raypipe::modes::{Accel, Builder, Integrator, MemoryMode, Pipeline};
use raypipe::scene::ToneMap;

/// What the panel shows.
pub struct Readout<'a> {
    pub scene: &'a str,
    pub adapter: &'a str,
    pub primitives: usize,
    pub size: (u32, u32),
    pub fps: f64,
    /// Milliseconds per frame, and whether they come from timestamp queries (else the wall clock).
    pub frame_ms: f64,
    pub timestamps: bool,
    pub mrays_per_s: f64,
    pub build_ms: Option<f64>,
    /// The acceleration modes the device offers (ray queries where it has them).
    pub accels: &'a [Accel],
    /// Samples per pixel gathered, and the cap.
    pub samples: (u32, u32),
    pub message: Option<&'a str>,
}

/// A moving scene's clock, as the panel shows and changes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Playback {
    /// Seconds into the motion.
    pub time: f32,
    /// Where the motion starts again; `None` for endless motion.
    pub duration: Option<f32>,
    /// Scene seconds per second.
    pub speed: f32,
}

pub const KEYS: &str = "drag: orbit · right or middle drag: pan · wheel: dolly · WASD/QE: fly · R: reset\n\
    I: integrator · G: pipeline · B: acceleration · M: memory · [ ]: depth · V: view · Space: pause · Y: vsync · P: screenshot · H: panel";

fn choose<T: Choice>(ui: &mut egui::Ui, label: &str, value: &mut T) {
    choose_from(ui, label, value, T::ALL);
}

/// [`choose`] among `offered` only.
fn choose_from<T: Choice>(ui: &mut egui::Ui, label: &str, value: &mut T, offered: &[T]) {
    egui::ComboBox::from_label(label)
        .selected_text(value.name())
        .show_ui(ui, |ui| {
            for &option in offered {
                ui.selectable_value(value, option, option.name())
                    .on_hover_text(option.about());
            }
        });
}

/// Draws the panel; returns the modes the user asked for. A moving scene's `playback` gets a time
/// slider (where its motion ends) and a speed, which change it in place.
pub fn draw(ctx: &egui::Context, modes: &Modes, readout: &Readout, playback: Option<&mut Playback>) -> Modes {
    let mut asked = *modes;
    egui::Window::new("raypipe")
        .anchor(egui::Align2::LEFT_TOP, [8.0, 8.0])
        .resizable(false)
        .collapsible(true)
        .show(ctx, |ui| {
            ui.label(format!(
                "{} · {} primitives · {}x{}",
                readout.scene, readout.primitives, readout.size.0, readout.size.1
            ));
            ui.label(readout.adapter);
            let clock = if readout.timestamps { "GPU" } else { "wall clock" };
            ui.label(format!(
                "{:.1} fps · {:.2} ms per frame ({clock}) · {:.2} M primary rays/s",
                readout.fps, readout.frame_ms, readout.mrays_per_s
            ));
            let (samples, cap) = readout.samples;
            let done = if samples >= cap { " (done)" } else { "" };
            ui.label(format!("{samples} of {cap} samples per pixel{done}"));
            match readout.build_ms {
                Some(ms) => ui.label(format!("BVH build: {ms:.2} ms")),
                None if modes.accel.needs_ray_queries() => ui.label("BVH build: the driver's, with ray queries"),
                None => ui.label("BVH build: none (brute force)"),
            };
            ui.separator();
            choose::<Integrator>(ui, "integrator", &mut asked.integrator);
            choose::<Pipeline>(ui, "pipeline", &mut asked.pipeline);
            choose_from(ui, "acceleration", &mut asked.accel, readout.accels);
            choose::<Builder>(ui, "BVH builder", &mut asked.builder);
            choose::<MemoryMode>(ui, "memory", &mut asked.memory);
            choose::<Aov>(ui, "view", &mut asked.view);
            choose::<ToneMap>(ui, "tone map", &mut asked.display.tone_map);
            ui.add(
                egui::Slider::new(&mut asked.display.exposure, -8.0..=8.0)
                    .step_by(0.25)
                    .text("exposure (EV)"),
            );
            ui.add(egui::Slider::new(&mut asked.depth, 0..=raypipe::scene::MAX_DEPTH_LIMIT).text("depth"));
            if let Some(playback) = playback {
                ui.checkbox(&mut asked.paused, "pause motion");
                match playback.duration {
                    Some(duration) if duration > 0.0 => {
                        ui.add(egui::Slider::new(&mut playback.time, 0.0..=duration).text("time (s)"));
                    }
                    _ => {
                        ui.label(format!("time {:.2} s", playback.time));
                    }
                }
                ui.add(egui::Slider::new(&mut playback.speed, 0.0..=4.0).text("speed"));
            }
            ui.checkbox(&mut asked.vsync, "vsync");
            if let Some(message) = readout.message {
                ui.separator();
                ui.colored_label(egui::Color32::from_rgb(255, 120, 100), message);
            }
            ui.separator();
            ui.small(KEYS);
        });
    asked
}
