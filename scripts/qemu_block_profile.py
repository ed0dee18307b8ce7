#!/usr/bin/env python3
"""Instructions per frame pixel spent in one firmware function, block by
block, from QEMU's translation-block trace (how the stereo engine's steps
were measured; docs/STEREO.md).

    cargo xtask firmware   # builds the ELF
    python3 scripts/qemu_block_profile.py \
        target/thumb/thumbv7em-none-eabihf/firmware/firmware-sim 'Refiner' [--runs 2]

The function is the first symbol of `arm-none-eabi-nm -C -S` whose name
contains the pattern; its address range is traced with `-d
in_asm,exec,nochain -dfilter`, each block weighted by its executions.
`--runs` divides by the number of stage runs that execute the function
(the firmware runs each operating point once; 2 for the two phase points).
Figures are per pixel of the 160x120 frame.
"""
import argparse
import collections
import re
import subprocess
import tempfile

PIXELS = 160 * 120


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("elf")
    ap.add_argument("pattern")
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--top", type=int, default=12)
    a = ap.parse_args()
    nm = subprocess.run(["arm-none-eabi-nm", "-C", "-S", a.elf], capture_output=True,
                        text=True, check=True).stdout
    sym = next(l for l in nm.splitlines() if a.pattern in l and len(l.split()) >= 4)
    start, size = int(sym.split()[0], 16), int(sym.split()[1], 16)
    with tempfile.NamedTemporaryFile(suffix=".log") as log:
        subprocess.run(["qemu-system-arm", "-machine", "mps2-an386", "-cpu", "cortex-m4",
                        "-nographic", "-semihosting-config", "enable=on,target=native",
                        "-icount", "shift=0", "-kernel", a.elf, "-d", "in_asm,exec,nochain",
                        "-dfilter", f"0x{start:x}..0x{start + size - 1:x}", "-D", log.name],
                       stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, timeout=1800,
                       check=True)
        blocks, execs, cur = {}, collections.Counter(), None
        with open(log.name, errors="replace") as f:
            for line in f:
                if line.startswith("IN:") or not line.strip():
                    cur = None
                    continue
                m = re.match(r"^0x([0-9a-f]{8}):\s", line)
                if m:
                    addr = int(m.group(1), 16)
                    if cur is None:
                        cur, blocks[addr] = addr, 0
                    blocks[cur] += 1
                    continue
                m = re.search(r"Trace \d+: 0x[0-9a-f]+ \[[0-9a-f]+/([0-9a-f]+)/", line)
                if m:
                    execs[int(m.group(1), 16)] += 1
    per = PIXELS * a.runs
    tot = {b: n * blocks.get(b, 0) for b, n in execs.items()}
    print(f"{sym.split(maxsplit=3)[3][:100]}")
    print(f"total {sum(tot.values()) / per:.1f} instructions per pixel and run")
    for b, v in sorted(tot.items(), key=lambda kv: -kv[1])[:a.top]:
        print(f"  block {b:08x}: {blocks[b]:3d} instructions x {execs[b] / per:6.3f} per pixel "
              f"= {v / per:5.1f}")


if __name__ == "__main__":
    main()
