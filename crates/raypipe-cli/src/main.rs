//! `raypipe`: the command line over the raypipe library, one file per subcommand. It owns what a
//! library must not: flags, progress bars, printing, and image and plot files.

mod args;
mod bench;
mod bench_motion;
mod bvh;
mod cli;
mod device;
mod diff;
mod info;
mod io;
mod notices;
mod plot;
mod render;
mod view;

use std::process::ExitCode;

fn main() -> ExitCode {
    notices::install();
    match cli::run() {
        Ok(code) => code,
        Err(error) => {
            if error
                .downcast_ref::<cli::StdoutError>()
                .is_some_and(|e| e.reader_left())
            {
                return ExitCode::from(2);
            }
            // One line, whatever the chain of causes: `error: FILE:LINE: what went wrong`.
            eprintln!("error: {}", cli::message(&error));
            ExitCode::from(2)
        }
    }
}
