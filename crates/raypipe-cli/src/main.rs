//! `raypipe`: the command line over the raypipe library, one file per subcommand. It owns what a
//! library must not: flags, progress bars, printing, and image and plot files.

use raypipe_cli::{cli, notices, report};
use std::process::ExitCode;

fn main() -> ExitCode {
    notices::install();
    match cli::run() {
        Ok(code) => code,
        Err(error) => {
            if error
                .downcast_ref::<report::StdoutError>()
                .is_some_and(|e| e.reader_left())
            {
                return ExitCode::from(2);
            }
            // One line, whatever the chain of causes: `error: FILE:LINE: what went wrong`.
            eprintln!("error: {}", report::message(&error));
            ExitCode::from(2)
        }
    }
}
