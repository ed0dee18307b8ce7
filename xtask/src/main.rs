//! Project automation: `cargo xtask <command>` (std only).

mod bench;
mod ci;
mod data;
mod firmware;
mod fuzz;
mod product;
mod setup;
mod util;

use std::process::ExitCode;

const USAGE: &str = "usage: cargo xtask <command>

commands:
  ci          fmt, clippy, fetch-data, tests, no_std core build, firmware under QEMU vs host
  fetch-data  download the aloe (Debian opencv-doc) and motorcycle (scikit-image wheel)
              stereo pairs into the data cache
  firmware    build the product and the bench firmware, run them under QEMU mps2-an386,
              the product for the STM32F405 under QEMU netduinoplus2 and the product
              with the accurate preset
  product     build the firmware, run only the product under QEMU mps2-an386 and
              netduinoplus2 (and with the accurate preset), and compare it with the
              host and the golden list
  bench       measure and write docs/BENCHMARKS.md
  fuzz [N]    run every fuzz target of host/tests/fuzz.rs for N cases (default 100000)
  setup       install missing system packages / rustup components";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("ci") => ci::run(),
        Some("fetch-data") => data::fetch().map(|_| ()),
        Some(cmd @ ("firmware" | "product")) => {
            let built = if cmd == "firmware" {
                firmware::build_and_run().map(|_| ())
            } else {
                firmware::build_product()
            };
            built
                .and_then(|()| product::run())
                .and_then(|p| {
                    println!(
                        "{} product lines equal on host, QEMU and {}\n{}",
                        p.lines,
                        product::GOLDEN,
                        p.report
                    );
                    println!("-- the product for the STM32F405 on QEMU netduinoplus2:");
                    product::run_f405(&p.qemu.stdout).map(|r| println!("{r}"))
                })
                .and_then(|()| {
                    println!("-- the product with the accurate preset on QEMU mps2-an386:");
                    product::run_accurate().map(|r| println!("{r}"))
                })
        }
        Some("bench") => bench::run(),
        Some("fuzz") => fuzz::run(&args[1..]),
        Some("setup") => setup::ensure_all(),
        Some("-h" | "--help" | "help") => {
            println!("{USAGE}");
            Ok(())
        }
        Some(other) => Err(format!("unknown command '{other}'\n{USAGE}")),
        None => Err(format!("no command given\n{USAGE}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: error: {e}");
            ExitCode::FAILURE
        }
    }
}
