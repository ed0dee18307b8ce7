//! The link-time proof that the firmware cannot panic: the panic entry
//! points an ELF links, and the functions that branch to them.

use std::process::Command;

use crate::util::{output, Result};

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
