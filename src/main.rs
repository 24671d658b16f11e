use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = dibench::cli::Cli::parse();
    match dibench::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            match e {
                // 128 + SIGINT, as a shell reports a command stopped by Ctrl-C.
                dibench::error::Error::Interrupted(_) => ExitCode::from(130),
                _ => ExitCode::FAILURE,
            }
        }
    }
}
