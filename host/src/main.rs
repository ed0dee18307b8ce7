//! `protogist`: the host command line. Without arguments it runs the demo.

use protogist_host::cli::{parse_args, run};
use std::process::ExitCode;

/// Exit code for a failed run (clap uses 2 for bad arguments).
const FAILURE: u8 = 1;

fn main() -> ExitCode {
    let cli = match parse_args(std::env::args_os()) {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help and --version: clap prints them to stdout.
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            // Keep clap's first line ("error: ..."), drop the usage block.
            let msg = e.to_string();
            let first = msg.lines().next().unwrap_or("error: bad arguments");
            eprintln!("{first} (see --help)");
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(summary) => {
            print!("{summary}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            // One line, whatever the underlying message holds.
            let msg = e.to_string().replace(['\n', '\r'], " ");
            eprintln!("error: {msg}");
            ExitCode::from(FAILURE)
        }
    }
}
