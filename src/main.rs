//! The `splitray` command line.

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format_timestamp(None)
        .init();
    let args = cli::Cli::from_command_line();
    match cli::run(args) {
        Ok(code) => code,
        Err(e) => {
            splitray::errln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
