use std::process::ExitCode;

fn main() -> ExitCode {
    match raypipe::cli::run() {
        Ok(code) => code,
        Err(error) => {
            // One line, whatever the chain of causes: `error: FILE:LINE: what went wrong`.
            eprintln!("error: {}", raypipe::gpu::context::one_line(&format!("{error:#}")));
            ExitCode::from(2)
        }
    }
}
