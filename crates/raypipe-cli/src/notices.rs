//! The library's notices (the `log` crate) as the command line shows them: one line each on
//! standard error, `notice:` or `warning:` first.

use log::{Level, LevelFilter, Log, Metadata, Record};

struct Notices;

impl Log for Notices {
    fn enabled(&self, metadata: &Metadata) -> bool {
        // wgpu's own logging stays quiet; raypipe's notices and everyone's warnings show.
        metadata.level() <= Level::Warn || metadata.target().starts_with("raypipe")
    }

    fn log(&self, record: &Record) {
        if !self.enabled(record.metadata()) {
            return;
        }
        let kind = match record.level() {
            Level::Error | Level::Warn => "warning",
            _ => "notice",
        };
        eprintln!("{kind}: {}", raypipe::error::one_line(&record.args().to_string()));
    }

    fn flush(&self) {}
}

pub fn install() {
    if log::set_logger(&Notices).is_ok() {
        log::set_max_level(LevelFilter::Info);
    }
}
