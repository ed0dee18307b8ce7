//! The memory budgets of the memory maps and the section sizes of a
//! firmware ELF against them.

use std::process::Command;

use super::{bench_elf, Machine};
use crate::util::{output, root, Result};

/// Parses `LENGTH = 2M` style values for FLASH and RAM from memory.x.
pub fn budget() -> Result<(u64, u64)> {
    budget_of(Machine::Mps2An386)
}

/// FLASH and RAM lengths of `machine`'s memory map.
pub fn budget_of(machine: Machine) -> Result<(u64, u64)> {
    Ok((
        region_length(machine, "FLASH")?,
        region_length(machine, "RAM")?,
    ))
}

/// The CCM region's length in the F405's QEMU map (`memory-f405-qemu.x`).
pub fn f405_ccm_budget() -> Result<u64> {
    region_length(Machine::Netduinoplus2, "CCM")
}

/// The bench firmware's memory map (mps2-an386's 4 MB of code SSRAM).
pub const BENCH_MAP: &str = "memory-bench.x";

/// The LENGTH of `region` in `machine`'s memory map (`64K`, `1M` or bytes).
fn region_length(machine: Machine, region: &str) -> Result<u64> {
    map_region_length(machine.memory_map(), region)
}

/// The LENGTH of `region` in firmware-sim/`name`.
fn map_region_length(name: &str, region: &str) -> Result<u64> {
    let path = root().join("firmware-sim").join(name);
    let text =
        std::fs::read_to_string(&path).map_err(|e| format!("reading {}: {e}", path.display()))?;
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

/// Section sizes of the bench firmware, summed against its map
/// ([`BENCH_MAP`]).
pub fn size_report() -> Result<String> {
    size_report_of(&bench_elf(), BENCH_MAP)
}

/// Section sizes of a firmware-sim ELF, summed against firmware-sim/`map`.
pub fn size_report_of(elf: &std::path::Path, map: &str) -> Result<String> {
    let Sizes {
        flash, ram, rows, ..
    } = sizes(elf)?;
    let (flash_budget, ram_budget) = (
        map_region_length(map, "FLASH")?,
        map_region_length(map, "RAM")?,
    );
    let pct = |a: u64, b: u64| a as f64 * 100.0 / b as f64;
    let report = format!(
        "{rows}  flash: {flash} / {flash_budget} B ({:.1}%)\n  RAM (static): {ram} / {ram_budget} B ({:.1}%), {} B left for the stack\n",
        pct(flash, flash_budget),
        pct(ram, ram_budget),
        ram_budget.saturating_sub(ram)
    );
    if flash > flash_budget || ram > ram_budget {
        return Err(format!("firmware exceeds the {map} budget:\n{report}"));
    }
    Ok(report)
}
