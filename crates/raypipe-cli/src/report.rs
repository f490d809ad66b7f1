//! How the command line reports: the one-line message an error becomes (the library's errors worded
//! in terms of the flags that avoid them), lines on standard output that fail instead of panicking,
//! and the medians its timings print.

use raypipe::gpu::GpuError;
use raypipe::modes::MemoryMode;

/// `error` and its causes on one line, with the library's errors worded in terms of the flags that
/// avoid them.
pub fn message(error: &anyhow::Error) -> String {
    let parts: Vec<String> = error
        .chain()
        .map(|cause| match cause.downcast_ref::<GpuError>() {
            Some(gpu) => gpu_message(gpu),
            None => cause.to_string(),
        })
        .collect();
    raypipe::error::one_line(&parts.join(": "))
}

fn gpu_message(error: &GpuError) -> String {
    match error {
        GpuError::TooBig {
            memory,
            array,
            records,
            needed,
            allowed,
        } => {
            let hint = match memory {
                MemoryMode::Uniform => "; use --memory storage",
                MemoryMode::Storage => "; use --memory texture, or --device cpu",
                MemoryMode::Texture => "; use --device cpu",
            };
            format!(
                "scene too big for --memory {memory}: {records} {array} records need {needed}, the adapter allows {allowed}{hint}"
            )
        }
        GpuError::RebuildNeedsStorage { .. } => {
            "the BVH rebuilt on the GPU is read from storage memory: use --memory storage".into()
        }
        GpuError::MissingBvh(missing) => format!("--accel {} needs the scene's BVH", missing.accel),
        GpuError::ImageTooLarge { width, height, max } => format!(
            "image {width}x{height} is larger than the adapter's maximum texture size {max}; render at most {max}x{max} on the GPU, or use --device cpu"
        ),
        GpuError::FrameTooLarge {
            width,
            height,
            bytes,
            max,
            max_pixels,
        } => format!(
            "image {width}x{height} needs {} MiB per frame target, the adapter allocates at most {} MiB; render at most {max_pixels} pixels on the GPU, or use --device cpu",
            bytes >> 20,
            max >> 20
        ),
        GpuError::PipelineUnsupported {
            adapter,
            pipeline,
            what,
        } => {
            format!("adapter {adapter} cannot {what}, which --pipeline {pipeline} needs")
        }
        other => other.to_string(),
    }
}

/// Standard output could not take a line: closed by its reader (a pipe into `head`) or full
/// (`> /dev/full`).
#[derive(Debug)]
pub struct StdoutError(pub std::io::Error);

impl std::fmt::Display for StdoutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "standard output: {}", self.0)
    }
}

impl std::error::Error for StdoutError {}

impl StdoutError {
    /// Whether the reader went away: nothing left to tell, so the command ends quietly.
    pub fn reader_left(&self) -> bool {
        self.0.kind() == std::io::ErrorKind::BrokenPipe
    }
}

/// `println!` that returns a [`StdoutError`] where `println!` would panic: standard output closed
/// or full.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*).map_err($crate::report::StdoutError)?
    }};
}

/// The most memory the process has held at once (its resident set's high-water mark, Linux's
/// `VmHWM`), in bytes; `None` where the system does not say. On lavapipe and llvmpipe the GPU's
/// buffers and textures live in it too.
pub fn peak_host_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|line| line.starts_with("VmHWM:"))?;
    let kib: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .strip_suffix("kB")?
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

/// The median of `values` (for an even count the mean of the middle two, as the peer benchmark
/// takes it); 0 for none.
pub fn median(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.into_iter().collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let half = v.len() / 2;
    if v.len().is_multiple_of(2) {
        (v[half - 1] + v[half]) / 2.0
    } else {
        v[half]
    }
}

/// Writes `rows` (each a struct serialized as an object) as CSV: a header of the fields' names,
/// nested objects' fields as `outer.inner`, null as an empty field, and a field that holds a
/// comma, a quote or a line break quoted (RFC 4180), so that a scene's or an adapter's name stays
/// one field. A nested object that is null in some rows leaves its fields empty there.
pub fn write_csv<T: serde::Serialize>(path: &std::path::Path, rows: &[T]) -> anyhow::Result<()> {
    use anyhow::Context;
    let mut flat = Vec::new();
    for row in rows {
        let mut fields = Vec::new();
        flatten(String::new(), serde_json::to_value(row)?, &mut fields);
        flat.push(fields);
    }
    // Every row's names in their order; a null that stands for an object another row has is
    // replaced by that object's fields.
    let mut header: Vec<String> = Vec::new();
    for fields in &flat {
        let mut at = 0;
        for (name, _) in fields {
            match header.iter().position(|h| h == name) {
                Some(i) => at = i + 1,
                None => {
                    header.insert(at, name.clone());
                    at += 1;
                }
            }
        }
    }
    let stands_for_object = |h: &String| header.iter().any(|other| other.starts_with(&format!("{h}.")));
    let header: Vec<String> = header.iter().filter(|h| !stands_for_object(h)).cloned().collect();
    let mut text = csv_line(header.iter().map(String::as_str));
    for fields in &flat {
        let value = |h: &String| {
            fields
                .iter()
                .find(|(name, _)| name == h)
                .map_or("", |(_, v)| v.as_str())
        };
        text += &csv_line(header.iter().map(value));
    }
    std::fs::write(path, text).with_context(|| format!("{}: cannot write", path.display()))
}

/// `value`'s leaves with their dotted names, in the order serde gives the fields.
fn flatten(name: String, value: serde_json::Value, out: &mut Vec<(String, String)>) {
    use serde_json::Value;
    match value {
        Value::Object(fields) => {
            for (key, value) in fields {
                let inner = if name.is_empty() { key } else { format!("{name}.{key}") };
                flatten(inner, value, out);
            }
        }
        Value::Null => out.push((name, String::new())),
        Value::String(text) => out.push((name, text)),
        other => out.push((name, other.to_string())),
    }
}

fn csv_line<'a>(fields: impl Iterator<Item = &'a str>) -> String {
    let quoted: Vec<String> = fields
        .map(|field| {
            if field.contains([',', '"', '\n', '\r']) {
                format!("\"{}\"", field.replace('"', "\"\""))
            } else {
                field.to_string()
            }
        })
        .collect();
    quoted.join(",") + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Serialize)]
    struct Phases {
        sort: f64,
    }

    #[derive(serde::Serialize)]
    struct Row {
        scene: &'static str,
        count: u32,
        build: Option<Phases>,
    }

    /// A name with a comma or a quote stays one field; nested fields are named by their path;
    /// missing ones are empty.
    #[test]
    fn csv_rows_quote_what_would_split_a_field() {
        let path = std::env::temp_dir().join(format!("raypipe-csv-{}.csv", std::process::id()));
        let rows = [
            Row {
                scene: "bunny, small \"a\"",
                count: 3,
                build: Some(Phases { sort: 0.5 }),
            },
            Row {
                scene: "plain",
                count: 4,
                build: None,
            },
        ];
        let first_empty = [
            Row {
                scene: "a",
                count: 1,
                build: None,
            },
            Row {
                scene: "b",
                count: 2,
                build: Some(Phases { sort: 0.25 }),
            },
        ];
        write_csv(&path, &rows).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(
            text,
            "scene,count,build.sort\n\"bunny, small \"\"a\"\"\",3,0.5\nplain,4,\n"
        );
        write_csv(&path, &first_empty).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(text, "scene,count,build.sort\na,1,\nb,2,0.25\n");
    }

    #[test]
    fn median_is_the_middle_value_or_the_mean_of_the_middle_two() {
        assert_eq!(median([]), 0.0);
        assert_eq!(median([3.0]), 3.0);
        assert_eq!(median([5.0, 1.0, 3.0]), 3.0);
        assert_eq!(median([4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median([1.0, 100.0]), 50.5);
    }

    /// A frame past the adapter's largest allocation says how big a frame fits and the way out.
    #[test]
    fn a_frame_too_large_says_what_fits_and_the_way_out() {
        let message = gpu_message(&GpuError::FrameTooLarge {
            width: 512,
            height: 512,
            bytes: 4 << 20,
            max: 1 << 20,
            max_pixels: 65536,
        });
        assert_eq!(
            message,
            "image 512x512 needs 4 MiB per frame target, the adapter allocates at most 1 MiB; render at most 65536 pixels on the GPU, or use --device cpu"
        );
    }
}

#[cfg(test)]
mod memory_tests {
    #[test]
    #[cfg(target_os = "linux")]
    fn the_peak_grows_with_what_the_process_holds() {
        let before = super::peak_host_bytes().expect("Linux says VmHWM");
        // More than the peak so far (whatever the other tests held), every page written, and kept
        // from the optimizer.
        let size = before as usize + (64 << 20);
        let held = std::hint::black_box(vec![1u8; size]);
        let after = super::peak_host_bytes().unwrap();
        assert!(after >= size as u64, "{before} then {after} with {size} bytes held");
        drop(held);
    }
}
