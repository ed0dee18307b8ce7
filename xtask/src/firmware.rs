//! Cortex-M builds (thumbv7em), QEMU runs and the memory budgets.

use std::io::Read;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::setup::{rustup_has_thumb, THUMB};
use crate::util::{host_cargo, output, root, Result};

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
    /// `memory.x`: every binary, the product at 160x120.
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
    let args = [
        "-p",
        "firmware-sim",
        "--bin",
        "firmware-sim",
        "--features",
        "f405",
    ];
    let what = "the product for the STM32F405 (firmware-sim --features f405, 128x96)";
    build_checked(
        &args,
        F405_TARGET_DIR,
        Machine::Netduinoplus2.memory_map(),
        what,
    )?;
    Ok(f405_elf())
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
    let args = [
        "-p",
        "firmware-sim",
        "--bin",
        "firmware-sim",
        "--features",
        "f405-board",
    ];
    let what = "the product for the STM32F405 board (firmware-sim --features f405-board)";
    build_checked(&args, F405_TARGET_DIR, "memory-f405.x", what)?;
    sizes(&f405_elf()).map_err(FirmwareError::Build)
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

/// Symbols whose presence in the linked ELF means a panic is reachable:
/// the panic entry points of `core` and the `#[panic_handler]`.
const PANIC_MARKERS: [&str; 2] = ["core::panicking::", "rust_begin_unwind"];

/// The symbols of `nm -C` output that are panic entry points.
pub fn panic_symbols(nm: &str) -> Vec<&str> {
    nm.lines()
        .filter_map(|l| l.splitn(3, ' ').nth(2))
        .filter(|name| PANIC_MARKERS.iter().any(|m| name.contains(m)))
        .collect()
}

/// The functions of `objdump -d -C` output that branch to a panic entry
/// point (`core::` itself excluded), each once, in address order.
pub fn panic_callers(objdump: &str) -> Vec<String> {
    let mut current: Option<&str> = None;
    let mut callers: Vec<String> = Vec::new();
    for line in objdump.lines() {
        // A function starts with `0001165e <name>:`.
        if let Some(name) = line
            .strip_suffix(">:")
            .and_then(|l| l.split_once(" <"))
            .map(|(_, name)| name)
        {
            current = Some(name);
            continue;
        }
        // `   addr:\tbytes\top\toperand`: a branch's operand is
        // `addr <name>` or `addr <name+0x4c>` (a branch inside `name`).
        let mut fields = line.split('\t').skip(2);
        let (Some(op), Some(operand)) = (fields.next(), fields.next()) else {
            continue;
        };
        let Some(target) = operand.split_once(" <").map(|(_, t)| t) else {
            continue;
        };
        let callee = target.strip_suffix('>').unwrap_or(target);
        let callee = callee.split_once("+0x").map_or(callee, |(name, _)| name);
        if op.starts_with('b') && PANIC_MARKERS.iter().any(|m| callee.contains(m)) {
            let caller = current.filter(|f| !f.starts_with("core::") && *f != callee);
            if let Some(f) = caller {
                if callers.last().map(String::as_str) != Some(f) {
                    callers.push(f.to_string());
                }
            }
        }
    }
    callers
}

/// Fails if the firmware ELF links any panic entry point: the link-time
/// proof that no panic is reachable (the optimiser removed every path, so
/// `--gc-sections` dropped `core`'s panic functions and the handler).
/// On failure, lists the functions that still branch to one.
pub fn check_no_panic(elf: &std::path::Path) -> Result<String> {
    let nm = output(Command::new("arm-none-eabi-nm").arg("-C").arg(elf))?;
    let found = panic_symbols(&nm);
    if found.is_empty() {
        return Ok(format!(
            "no panic path: {} links none of {PANIC_MARKERS:?}",
            elf.display()
        ));
    }
    let dis = output(
        Command::new("arm-none-eabi-objdump")
            .args(["-d", "-C"])
            .arg(elf),
    )?;
    let callers = panic_callers(&dis);
    let mut msg = format!(
        "{} can panic: it links {} panic symbol(s):\n",
        elf.display(),
        found.len()
    );
    for s in &found {
        msg.push_str(&format!("  {s}\n"));
    }
    msg.push_str("called from:\n");
    for c in &callers {
        msg.push_str(&format!("  {c}\n"));
    }
    msg.push_str("(`arm-none-eabi-addr2line -i -e ELF ADDR` on a call site gives its source line)");
    Err(msg)
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

/// Parses `LENGTH = 2M` style values for FLASH and RAM from memory.x.
pub fn budget() -> Result<(u64, u64)> {
    budget_of(Machine::Mps2An386)
}

/// FLASH and RAM lengths of `machine`'s memory map.
pub fn budget_of(machine: Machine) -> Result<(u64, u64)> {
    let name = machine.memory_map();
    let path = root().join("firmware-sim").join(name);
    let text =
        std::fs::read_to_string(&path).map_err(|e| format!("reading {}: {e}", path.display()))?;
    let length = |region: &str| -> Result<u64> {
        let line = text
            .lines()
            .find(|l| l.trim_start().starts_with(region) && l.contains("LENGTH"))
            .ok_or(format!("{name} has no {region} region"))?;
        let v = line
            .split("LENGTH")
            .nth(1)
            .unwrap_or("")
            .trim_start_matches([' ', '='])
            .trim();
        let (num, mult) = match v.chars().last() {
            Some('K') => (&v[..v.len() - 1], 1024),
            Some('M') => (&v[..v.len() - 1], 1024 * 1024),
            _ => (v, 1),
        };
        num.parse::<u64>()
            .map(|n| n * mult)
            .map_err(|_| format!("{name}: cannot parse LENGTH '{v}'"))
    };
    Ok((length("FLASH")?, length("RAM")?))
}

/// The CCM region's length in the F405's QEMU map (`memory-f405-qemu.x`).
pub fn f405_ccm_budget() -> Result<u64> {
    let name = Machine::Netduinoplus2.memory_map();
    let path = root().join("firmware-sim").join(name);
    let text =
        std::fs::read_to_string(&path).map_err(|e| format!("reading {}: {e}", path.display()))?;
    text.lines()
        .find(|l| l.trim_start().starts_with("CCM") && l.contains("LENGTH"))
        .and_then(|l| l.split("LENGTH").nth(1))
        .map(|v| v.trim_start_matches([' ', '=']).trim())
        .and_then(|v| v.strip_suffix('K')?.parse::<u64>().ok())
        .map(|k| k * 1024)
        .ok_or(format!("{name} has no CCM region in K"))
}

/// Bytes of an ELF in flash and in static RAM, and its section rows.
pub struct Sizes {
    pub flash: u64,
    /// Static RAM, `.ccm` included.
    pub ram: u64,
    /// Of it, section `.ccm` (the pipeline's kept maps): the STM32F405's
    /// core-coupled RAM on its maps, ordinary RAM on mps2-an386's.
    pub ccm: u64,
    pub rows: String,
}

/// Section sizes of `elf` from `arm-none-eabi-size -A`.
pub fn sizes(elf: &std::path::Path) -> Result<Sizes> {
    let text = output(Command::new("arm-none-eabi-size").arg("-A").arg(elf))?;
    let (mut flash, mut ram, mut ccm, mut rows) = (0u64, 0u64, 0u64, String::new());
    for line in text.lines() {
        let mut it = line.split_whitespace();
        let (Some(name), Some(size)) = (it.next(), it.next().and_then(|s| s.parse::<u64>().ok()))
        else {
            continue;
        };
        let in_flash = matches!(
            name,
            ".vector_table" | ".text" | ".rodata" | ".data" | ".gnu.sgstubs"
        );
        let in_ram = matches!(name, ".data" | ".bss" | ".uninit" | ".ccm");
        ccm += if name == ".ccm" { size } else { 0 };
        if in_flash || in_ram {
            rows.push_str(&format!("  {name:<14} {size:>8} B\n"));
        }
        flash += if in_flash { size } else { 0 };
        ram += if in_ram { size } else { 0 };
    }
    Ok(Sizes {
        flash,
        ram,
        ccm,
        rows,
    })
}

/// Section sizes of the bench firmware, summed against memory.x.
pub fn size_report() -> Result<String> {
    size_report_of(&bench_elf())
}

/// Section sizes of a firmware-sim ELF, summed against memory.x.
pub fn size_report_of(elf: &std::path::Path) -> Result<String> {
    let Sizes {
        flash, ram, rows, ..
    } = sizes(elf)?;
    let (flash_budget, ram_budget) = budget()?;
    let pct = |a: u64, b: u64| a as f64 * 100.0 / b as f64;
    let report = format!(
        "{rows}  flash: {flash} / {flash_budget} B ({:.1}%)\n  RAM (static): {ram} / {ram_budget} B ({:.1}%), {} B left for the stack\n",
        pct(flash, flash_budget),
        pct(ram, ram_budget),
        ram_budget.saturating_sub(ram)
    );
    if flash > flash_budget || ram > ram_budget {
        return Err(format!("firmware exceeds the memory.x budget:\n{report}"));
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    const NM: &str = "\
0000f60e t __rustc::rust_begin_unwind
000115cc t core::panicking::panic_fmt
00012362 t core::panicking::panic_const::panic_const_div_by_zero
00022e40 t <protogist::stereo::c2f::Pass>::votes
";

    const DIS: &str = "\
00022e40 <<protogist::stereo::c2f::Pass>::votes>:
   22e40:\tb5f0      \tpush\t{r4, r5, r6, r7, lr}
   22fa4:\tf002 8263 \tbeq.w\t2546e <<protogist::stereo::c2f::Pass>::votes+0x262e>
   25476:\tf7ed f8a9 \tbl\t12362 <core::panicking::panic_const::panic_const_div_by_zero>
   25480:\tf7ed f8a9 \tbl\t115cc <core::panicking::panic_fmt>

00030000 <firmware_sim::mcu::run<cortex_m_semihosting::hio::HostStream>>:
   30004:\tf7ed f8a9 \tbl\t11700 <core::panicking::assert_failed<usize, usize>>

0002547a <<protogist::stereo::c2f::Pass>::decision>:
   2547a:\tb5f0      \tpush\t{r4, r5, r6, r7, lr}
   2547c:\tf7ed f8a9 \tbl\t2547a <<protogist::stereo::c2f::Pass>::decision>

000115cc <core::panicking::panic_fmt>:
   115d0:\tf7ed f8a9 \tbl\tf60e <__rustc::rust_begin_unwind>
   115d4:\t6818      \tldr\tr0, [r3, #0]\t@ <core::panicking::panic_fmt>

0000f60e <__rustc::rust_begin_unwind>:
   f630:\tf7ed f8a9 \tb.n\tf65a <__rustc::rust_begin_unwind+0x4c>
";

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

    #[test]
    fn panic_symbols_finds_the_entry_points_only() {
        assert_eq!(
            panic_symbols(NM),
            [
                "__rustc::rust_begin_unwind",
                "core::panicking::panic_fmt",
                "core::panicking::panic_const::panic_const_div_by_zero"
            ]
        );
        let clean: String = NM.lines().skip(3).map(|l| format!("{l}\n")).collect();
        assert!(panic_symbols(&clean).is_empty());
    }

    #[test]
    fn panic_callers_names_each_branching_function_once() {
        // `run` calls a generic panic function. Not `decision` (it branches
        // to itself), not core's own panic_fmt, not the handler's branches
        // inside itself, and a load that merely names a panic symbol is not
        // a branch.
        assert_eq!(
            panic_callers(DIS),
            [
                "<protogist::stereo::c2f::Pass>::votes",
                "firmware_sim::mcu::run<cortex_m_semihosting::hio::HostStream>"
            ]
        );
    }
}
