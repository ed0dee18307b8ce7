//! `ci`: every check, in order, stopping at the first failure.

use crate::firmware::{build_and_run, build_thumb, compare, host_output, size_report};
use crate::util::{self, host_cargo, step, Result};
use crate::{data, product, setup};

/// Wall time per step, and (passed, failed, ignored) test counts.
type CiSummary = (Vec<(&'static str, f64)>, (u64, u64, u64));

/// The test that trains the shipped model again (host/tests/shipped_model.rs).
const SHIPPED_REGEN: &str = "documented_commands_regenerate_the_shipped_model";

pub fn run_ci() -> Result<CiSummary> {
    let mut times = Vec::new();
    let mut timed = |name: &'static str, secs: f64| times.push((name, secs));

    let (_, t) = step(
        "setup: system packages and rustup components",
        setup::ensure_all,
    )?;
    timed("setup", t);
    let (_, t) = step("fmt: cargo fmt --all -- --check", || {
        util::run(host_cargo().args(["fmt", "--all", "--", "--check"]))
    })?;
    timed("fmt", t);
    let (_, t) = step(
        "clippy: cargo clippy --workspace --all-targets -- -D warnings",
        || {
            util::run(host_cargo().args([
                "clippy",
                "--locked",
                "--workspace",
                "--all-targets",
                "--",
                "-D",
                "warnings",
            ]))
        },
    )?;
    timed("clippy", t);
    let (_, t) = step(
        "doc: cargo doc --workspace --no-deps --lib, warnings denied",
        || {
            // Libraries only: the host binary shares core's crate name.
            util::run(
                host_cargo()
                    .args(["doc", "--locked", "--workspace", "--no-deps", "--lib"])
                    .env("RUSTDOCFLAGS", "-D warnings"),
            )
        },
    )?;
    timed("doc", t);
    let (_, t) = step("fetch-data: aloe and motorcycle stereo pairs", data::fetch)?;
    timed("fetch-data", t);
    let (totals, t) = step("test: cargo test --workspace", || {
        // The real-data tests must not skip in CI: a missing file fails them.
        // The fuzz targets (host/tests/fuzz.rs) run here with their short
        // budget; `cargo xtask fuzz` runs them long.
        // The shipped model's regeneration runs in the next step.
        let mut cmd = host_cargo();
        cmd.args([
            "test",
            "--locked",
            "--workspace",
            "--",
            "--skip",
            SHIPPED_REGEN,
        ])
        .env("PROTOGIST_REQUIRE_DATA", "1");
        let out = util::run_tee(&mut cmd)?;
        Ok(util::test_totals(&out))
    })?;
    timed("test", t);
    let (regen, t) = step(
        "shipped model: the documented commands regenerate it bit for bit (release)",
        || {
            // Release, as the documented `protogist train` runs: its training
            // is a third faster than in the test profile (about 2,000 s
            // against 2,983 s on the 2-core machine, 2026-11-29), with the
            // same bytes.
            let mut cmd = host_cargo();
            cmd.args([
                "test",
                "--locked",
                "--release",
                "-p",
                "protogist-host",
                "--test",
                "shipped_model",
                SHIPPED_REGEN,
            ]);
            let out = util::run_tee(&mut cmd)?;
            Ok(util::test_totals(&out))
        },
    )?;
    timed("shipped model", t);
    let totals = (totals.0 + regen.0, totals.1 + regen.1, totals.2 + regen.2);
    let (_, t) = step(
        "no_std: build core (protogist) for thumbv7em-none-eabihf",
        || Ok(build_thumb("protogist")?),
    )?;
    timed("no_std core", t);
    let ((qemu, lines), t) = step(
        "firmware: the bench on QEMU mps2-an386 vs host, bit for bit",
        || {
            let qemu = build_and_run()?;
            println!("-- host run of firmware-sim:");
            let host = host_output()?;
            let lines = compare(&host, &qemu.stdout)?;
            println!(
                "-- bench firmware ELF against memory-bench.x:\n{}",
                size_report()?
            );
            Ok((qemu, lines))
        },
    )?;
    timed("firmware", t);
    let (product, t) = step(
        "product: core's pipeline on QEMU vs host vs the golden list",
        product::run,
    )?;
    println!(
        "{} product lines equal on host, QEMU and {} (QEMU run {:.1} s)\n{}",
        product.lines,
        product::GOLDEN,
        product.qemu.secs,
        product.report
    );
    timed("product", t);
    let (_, t) = step("instructions per pixel (QEMU -icount, SysTick)", || {
        println!(
            "{lines} checksum/edges lines equal on host and QEMU (QEMU run {:.1} s)",
            qemu.secs
        );
        for l in qemu.stdout.lines().filter(|l| {
            ["ipp ", "calib ", "stack "]
                .iter()
                .any(|p| l.starts_with(p))
        }) {
            println!("{l}");
        }
        Ok(())
    })?;
    timed("ipp", t);
    let (report, t) = step(
        "accurate: the product with the accurate preset on QEMU vs host",
        product::run_accurate,
    )?;
    println!("{report}");
    timed("accurate", t);
    // Last, so that every other check has run when the F405 does not fit.
    let (report, t) = step(
        "f405: the product at 128x96 on QEMU netduinoplus2 vs host, in 192 KB",
        || product::run_f405(&product.qemu.stdout),
    )?;
    println!("{report}");
    timed("f405", t);
    Ok((times, totals))
}

pub fn run() -> Result<()> {
    let start = std::time::Instant::now();
    let (times, (passed, failed, ignored)) = run_ci()?;
    println!(
        "\nci: all steps passed in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    for (name, secs) in times {
        println!("  {name:<12} {secs:>7.1} s");
    }
    println!("tests: {passed} passed, {failed} failed, {ignored} skipped");
    Ok(())
}
