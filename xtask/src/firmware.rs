//! Cortex-M builds (thumbv7em), QEMU runs and the memory budgets.

use std::io::Read;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::setup::{rustup_has_thumb, THUMB};
use crate::util::{host_cargo, output, root, Result};

mod budget;
mod panics;

pub use budget::{budget, budget_of, f405_ccm_budget, size_report, sizes, Sizes};
pub use panics::check_no_panic;

const QEMU_TIMEOUT: Duration = Duration::from_secs(300);
/// Lines that must be bit-identical between the host and the QEMU run.
const COMPARED_PREFIXES: [&str; 2] = ["checksum ", "edges "];

/// The bench firmware's ELF (`firmware-sim/src/bin/bench/`).
pub fn bench_elf() -> PathBuf {
    thumb_bin("bench")
}

/// The product's ELF for mps2-an386 (`firmware-sim/src/main.rs`, the
/// crate's default binary).
pub fn product_elf() -> PathBuf {
    thumb_bin("firmware-sim")
}

/// The ELF of one firmware-sim binary of the thumbv7em build.
fn thumb_bin(name: &str) -> PathBuf {
    thumb_dir("target/thumb").join(name)
}

fn thumb_dir(target_dir: &str) -> PathBuf {
    root().join(target_dir).join(THUMB).join("firmware")
}

/// A QEMU machine the firmware runs on, with its memory map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Machine {
    /// mps2-an386 (Cortex-M4, 4 MB code and data SSRAM), linked with
    /// `memory.x`: the product at 160x120 and the panic probe; the bench
    /// firmware with `memory-bench.x` (the whole 4 MB of code SSRAM).
    Mps2An386,
    /// netduinoplus2 (the STM32F405: 1 MB flash, 192 KB SRAM), linked with
    /// `memory-f405-qemu.x`: the product at 128x96 (the `f405` feature).
    Netduinoplus2,
}

impl Machine {
    /// QEMU's `-machine` name.
    pub fn qemu_name(self) -> &'static str {
        match self {
            Self::Mps2An386 => "mps2-an386",
            Self::Netduinoplus2 => "netduinoplus2",
        }
    }

    /// The linker script of the machine's map, in firmware-sim/.
    pub fn memory_map(self) -> &'static str {
        match self {
            Self::Mps2An386 => "memory.x",
            Self::Netduinoplus2 => "memory-f405-qemu.x",
        }
    }
}

/// The product's ELF for the STM32F405 (QEMU netduinoplus2): the default
/// binary with the `f405` feature, in its own target directory so that it
/// does not replace the mps2-an386 build's.
pub fn f405_elf() -> PathBuf {
    thumb_dir(F405_TARGET_DIR).join("firmware-sim")
}

const F405_TARGET_DIR: &str = "target/thumb-f405";

/// The product ELF with the accurate preset ([`build_accurate`]).
pub fn accurate_elf() -> PathBuf {
    thumb_dir(ACCURATE_TARGET_DIR).join("firmware-sim")
}

const ACCURATE_TARGET_DIR: &str = "target/thumb-accurate";

/// Why a firmware build or run failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FirmwareError {
    /// The linker could not fit the ELF into a region of its memory map.
    Overflow {
        /// The binary.
        elf: String,
        /// Its memory map (firmware-sim/…).
        map: &'static str,
        /// The region, e.g. `RAM`.
        region: String,
        /// Bytes beyond the region's end.
        by: u64,
    },
    /// The build failed otherwise; the command and its status.
    Build(String),
}

impl std::fmt::Display for FirmwareError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Overflow {
                elf,
                map,
                region,
                by,
            } => write!(
                f,
                "{elf} does not fit firmware-sim/{map}: region {region} overflowed by {by} bytes"
            ),
            Self::Build(what) => f.write_str(what),
        }
    }
}

impl From<FirmwareError> for String {
    fn from(e: FirmwareError) -> Self {
        e.to_string()
    }
}

/// The overflows GNU ld reports (``region `RAM' overflowed by 74064
/// bytes``), as (region, bytes).
pub fn overflows(linker_output: &str) -> Vec<(String, u64)> {
    linker_output
        .lines()
        .filter_map(|l| {
            let rest = l.split("region `").nth(1)?;
            let (region, rest) = rest.split_once('\'')?;
            let by = rest.strip_prefix(" overflowed by ")?;
            let by = by.split_whitespace().next()?.parse().ok()?;
            Some((region.to_string(), by))
        })
        .collect()
}

/// Builds the product for the STM32F405 (`--features f405`, 128x96,
/// `memory-f405-qemu.x`) into its own target directory.
///
/// # Errors
/// [`FirmwareError::Overflow`] when the linker cannot fit it (the largest
/// overflow it names), else [`FirmwareError::Build`].
pub fn build_f405() -> std::result::Result<PathBuf, FirmwareError> {
    let what = "the product for the STM32F405 (firmware-sim --features f405, 128x96)";
    build_product_with(
        "f405",
        F405_TARGET_DIR,
        Machine::Netduinoplus2.memory_map(),
        what,
    )?;
    Ok(f405_elf())
}

/// The product with the accurate preset at 160x120 (`--features
/// accurate`, mps2-an386's map: its RAM is over the default's 256 KB and
/// within `memory.x`'s 512 KB).
///
/// # Errors
/// As [`build_f405`].
pub fn build_accurate() -> std::result::Result<PathBuf, FirmwareError> {
    let what = "the product with the accurate preset (firmware-sim --features accurate)";
    build_product_with(
        "accurate",
        ACCURATE_TARGET_DIR,
        Machine::Mps2An386.memory_map(),
        what,
    )?;
    Ok(accurate_elf())
}

/// Links the F405 product with the real part's map (`--features
/// f405-board`, `memory-f405.x`: the kept maps in the CCM at 0x10000000,
/// the rest and the stack in the SRAM), which no QEMU machine runs: the
/// linker checks that each part fits. Replaces [`f405_elf`]'s ELF, so run
/// the QEMU build first.
///
/// # Errors
/// As [`build_f405`].
pub fn link_f405_board() -> std::result::Result<Sizes, FirmwareError> {
    let what = "the product for the STM32F405 board (firmware-sim --features f405-board)";
    build_product_with("f405-board", F405_TARGET_DIR, "memory-f405.x", what)?;
    sizes(&f405_elf()).map_err(FirmwareError::Build)
}

/// The product ELF (`firmware-sim`'s default binary) with `feature`, into
/// `target_dir`, linked against `map` ([`build_checked`]).
fn build_product_with(
    feature: &str,
    target_dir: &str,
    map: &'static str,
    what: &str,
) -> std::result::Result<(), FirmwareError> {
    let args = [
        "-p",
        "firmware-sim",
        "--bin",
        "firmware-sim",
        "--features",
        feature,
    ];
    build_checked(&args, target_dir, map, what)
}

/// `cargo build --profile firmware` for thumbv7em: rustup's prebuilt target if it
/// is installed, else Debian's toolchain with `-Zbuild-std=core`; the
/// mps2-an386 build (`memory.x`).
///
/// # Errors
/// [`FirmwareError::Overflow`] when an ELF does not fit `memory.x`, else
/// [`FirmwareError::Build`].
pub fn build_thumb(package: &str) -> std::result::Result<(), FirmwareError> {
    let what = format!("{package} for mps2-an386");
    build_checked(
        &["-p", package],
        "target/thumb",
        Machine::Mps2An386.memory_map(),
        &what,
    )
}

/// Runs a thumbv7em build of `args` into `target_dir`, linked with
/// `machine`'s map, passing its output through; a linker overflow becomes
/// a typed [`FirmwareError::Overflow`] naming `what`.
fn build_checked(
    args: &[&str],
    target_dir: &str,
    map: &'static str,
    what: &str,
) -> std::result::Result<(), FirmwareError> {
    let mut cmd = thumb_cargo(args, target_dir);
    let line = format!("{cmd:?}");
    println!("$ {line}");
    let out = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::inherit())
        .output()
        .map_err(|e| FirmwareError::Build(format!("cannot start cargo: {e}")))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprint!("{stderr}");
    if out.status.success() {
        return Ok(());
    }
    match overflows(&stderr).into_iter().max_by_key(|o| o.1) {
        Some((region, by)) => Err(FirmwareError::Overflow {
            elf: what.to_string(),
            map,
            region,
            by,
        }),
        None => Err(FirmwareError::Build(format!(
            "`{line}` failed ({})",
            out.status
        ))),
    }
}

/// The `cargo build --profile firmware` command for thumbv7em with `args`
/// into `target_dir` (see [`build_thumb`]).
fn thumb_cargo(args: &[&str], target_dir: &str) -> Command {
    let common = [
        "build",
        "--locked",
        "--profile",
        "firmware",
        "--target",
        THUMB,
        "--target-dir",
    ];
    let target_dir = root().join(target_dir);
    if rustup_has_thumb() {
        println!("using rustup's {THUMB} target");
        let mut cmd = host_cargo();
        cmd.args(common).arg(&target_dir).args(args);
        return cmd;
    }
    println!("rustup has no {THUMB} target: using Debian's cargo with -Zbuild-std=core");
    let mut cmd = Command::new("/usr/bin/cargo");
    cmd.current_dir(root())
        .args(common)
        .arg(&target_dir)
        .args(args)
        .arg("-Zbuild-std=core")
        .env("RUSTC_BOOTSTRAP", "1")
        .env("RUSTC", "/usr/bin/rustc")
        .env("RUSTDOC", "/usr/bin/rustdoc")
        .env_remove("RUSTUP_TOOLCHAIN")
        .env_remove("RUSTC_WRAPPER")
        .env_remove("CARGO_TARGET_DIR");
    cmd
}

pub struct QemuRun {
    pub stdout: String,
    pub secs: f64,
}

/// Runs an ELF on `machine` with semihosting; fails unless it exits with
/// success. Both machines are Cortex-M4s.
pub fn run_qemu(machine: Machine, elf: &std::path::Path) -> Result<QemuRun> {
    let mut cmd = Command::new("qemu-system-arm");
    cmd.args([
        "-machine",
        machine.qemu_name(),
        "-cpu",
        "cortex-m4",
        "-nographic",
    ])
    .args([
        "-semihosting-config",
        "enable=on,target=native",
        "-icount",
        "shift=0",
        "-kernel",
    ])
    .arg(elf)
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::inherit());
    println!("$ qemu-system-arm -machine {} -cpu cortex-m4 -nographic -semihosting-config enable=on,target=native -icount shift=0 -kernel {}", machine.qemu_name(), elf.display());
    let start = Instant::now();
    let mut child = cmd
        .spawn()
        .map_err(|e| format!("cannot start qemu-system-arm: {e}"))?;
    let mut pipe = child.stdout.take().ok_or("no stdout pipe from qemu")?;
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        pipe.read_to_string(&mut s).map(|_| s)
    });
    let status = loop {
        if let Some(status) = child
            .try_wait()
            .map_err(|e| format!("waiting for qemu: {e}"))?
        {
            break status;
        }
        if start.elapsed() > QEMU_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!(
                "qemu did not exit within {} s",
                QEMU_TIMEOUT.as_secs()
            ));
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stdout = reader
        .join()
        .map_err(|_| "qemu output reader panicked")?
        .map_err(|e| format!("reading qemu output: {e}"))?;
    print!("{stdout}");
    if !status.success() {
        return Err(format!(
            "firmware under QEMU did not exit with semihosting success ({status})"
        ));
    }
    Ok(QemuRun {
        stdout,
        secs: start.elapsed().as_secs_f64(),
    })
}

/// Builds firmware-sim for thumbv7em, checks that neither the product
/// (core's pipeline, `firmware-sim/src/main.rs`), the bench firmware nor
/// the panic probe (every core stage on opaque inputs,
/// `firmware-sim/src/probe.rs`) links a panic path ([`check_no_panic`]),
/// and runs the bench firmware under QEMU mps2-an386.
pub fn build_and_run() -> Result<QemuRun> {
    build_thumb("firmware-sim")?;
    for bin in [product_elf(), bench_elf(), thumb_bin("panic-probe")] {
        println!("{}", check_no_panic(&bin)?);
    }
    run_qemu(Machine::Mps2An386, &bench_elf())
}

/// Builds the firmware and checks that the product's ELF cannot panic,
/// without running the bench firmware (`cargo xtask product`).
pub fn build_product() -> Result<()> {
    build_thumb("firmware-sim")?;
    println!("{}", check_no_panic(&product_elf())?);
    Ok(())
}

/// Output of the host build of the bench firmware.
pub fn host_output() -> Result<String> {
    let out = output(host_cargo().args([
        "run",
        "--locked",
        "--quiet",
        "-p",
        "firmware-sim",
        "--release",
        "--bin",
        "bench",
    ]))?;
    print!("{out}");
    Ok(out)
}

pub fn compared_lines(out: &str) -> Vec<&str> {
    out.lines()
        .filter(|l| COMPARED_PREFIXES.iter().any(|p| l.starts_with(p)))
        .collect()
}

/// Requires the host and QEMU checksum lines to be equal and non-empty.
pub fn compare(host: &str, qemu: &str) -> Result<usize> {
    let (h, q) = (compared_lines(host), compared_lines(qemu));
    if h.is_empty() {
        return Err("host run printed no checksum lines".into());
    }
    if h != q {
        let mut msg = String::from("host and QEMU outputs differ:");
        for i in 0..h.len().max(q.len()) {
            let (a, b) = (
                h.get(i).copied().unwrap_or("<none>"),
                q.get(i).copied().unwrap_or("<none>"),
            );
            if a != b {
                msg.push_str(&format!("\n  host: {a}\n  qemu: {b}"));
            }
        }
        return Err(msg);
    }
    Ok(h.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overflows_reads_gnu_ld_regions() {
        let ld = "ld: x section `.bss' will not fit in region `RAM'\n\
                  ld: region `RAM' overflowed by 74064 bytes\n\
                  ld: region `FLASH' overflowed by 12 bytes\n\
                  collect2: error: ld returned 1 exit status\n";
        assert_eq!(
            overflows(ld),
            [("RAM".to_string(), 74064), ("FLASH".to_string(), 12)]
        );
        assert!(overflows("error: could not compile `firmware-sim`").is_empty());
        let e = FirmwareError::Overflow {
            elf: "p".into(),
            map: "memory-f405-qemu.x",
            region: "RAM".into(),
            by: 74064,
        };
        assert_eq!(
            String::from(e),
            "p does not fit firmware-sim/memory-f405-qemu.x: region RAM overflowed by 74064 bytes"
        );
    }
}
