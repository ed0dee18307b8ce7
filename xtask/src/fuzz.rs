//! `fuzz`: the fuzz targets of `host/tests/fuzz.rs` run long, in release.
//!
//! `cargo xtask fuzz [CASES]` runs every target for CASES cases (default
//! 100000) and prints one line per target with its count and time, to be
//! recorded in docs/FUZZ.md. `cargo test` (and so `cargo xtask ci`) runs
//! the same targets with a short budget.

use crate::util::{host_cargo, run_tee, Result};
use std::time::Instant;

/// Cases per target when none is given.
pub const DEFAULT_CASES: u64 = 100_000;

pub fn run(args: &[String]) -> Result<()> {
    let cases = match args.first() {
        Some(n) => n
            .parse::<u64>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("fuzz: CASES must be a positive integer, got '{n}'"))?,
        None => DEFAULT_CASES,
    };
    let start = Instant::now();
    let mut cmd = host_cargo();
    cmd.args([
        "test",
        "--release",
        "-p",
        "protogist-host",
        "--test",
        "fuzz",
        "--",
        "--test-threads",
        "1",
    ])
    .env("PROTOGIST_FUZZ_CASES", cases.to_string());
    let out = run_tee(&mut cmd)?;
    let targets: Vec<&str> = out
        .lines()
        .filter_map(|l| l.strip_prefix("test ")?.strip_suffix(" ... ok"))
        .collect();
    if targets.is_empty() {
        return Err("fuzz: no target ran".into());
    }
    println!(
        "\nfuzz: {} targets, {cases} cases each, all passed in {:.1} s",
        targets.len(),
        start.elapsed().as_secs_f64()
    );
    for t in targets {
        println!("  {t:<28} {cases} cases");
    }
    Ok(())
}
