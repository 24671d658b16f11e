use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = dibench::cli::Cli::parse();
    match dibench::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
