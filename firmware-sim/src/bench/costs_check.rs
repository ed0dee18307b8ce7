//! The read-out's cost kernel's self-test ([`costs_kernel_check`]).

use core::fmt::{self, Write};

use crate::pg::checksum::Fnv1a;
use crate::pg::rng::SplitMix64;
use crate::pg::stereo::phase::PhaseKernel;
use crate::pg::stereo::DemTable;
use crate::Aligned;

/// Pixels of the self-test.
pub const COSTS_STEPS: usize = 20_000;

/// Bytes of the bench's level-2 table, the self-test's template.
const CRAFT_LEN: usize = 856;

/// The self-test's own table: the bench's level-2 table with fraction
/// bits `wf`, `bf` and every bias from `bias`, checksum renewed; `None`
/// if the template is not a table of [`CRAFT_LEN`] bytes.
fn craft(buf: &mut [u8; CRAFT_LEN], wf: u8, bf: u8, mut bias: impl FnMut() -> i16) -> Option<()> {
    buf.copy_from_slice(super::stereo_run::TABLES[2].get(..CRAFT_LEN)?);
    let n = usize::from(*buf.get(8)?) + 1;
    *buf.get_mut(13)? = wf;
    *buf.get_mut(14)? = bf;
    let body = CRAFT_LEN - 4;
    for b in buf.get_mut(body - 2 * n..body)?.chunks_exact_mut(2) {
        b.copy_from_slice(&bias().to_le_bytes());
    }
    let mut f = Fnv1a::new();
    f.write(buf.get(..body)?);
    buf.get_mut(body..)?
        .copy_from_slice(&f.finish().to_le_bytes());
    Some(())
}

/// The cost kernel's self-test: [`COSTS_STEPS`] random pixels through
/// `K::costs` with windows of 5 and 9, their costs folded into a checksum. Half of them use the
/// decoder tables of levels 1 and 2 of the product's point and of the
/// bench's, the other half tables of the self-test's own (renewed every 64
/// pixels) with any fraction bits and biases all equal, small or of any
/// size, so that small score spans and both shift directions occur; any
/// window of a table, totals from 1 to 2^48 (log-uniform), scores within
/// the engine's bound `±(2^14·total + 2^27)` spread over a random number
/// of bits (one pixel in eight with all scores equal). The firmware runs
/// it with its assembly kernel and the desktop build with the portable
/// step; xtask requires the two `checksum costs-kernel` lines to be equal.
pub fn costs_kernel_check<K: PhaseKernel>() -> u32 {
    let product = crate::product::TABLES;
    let blobs = [
        product.get(1).copied(),
        product.get(2).copied(),
        super::stereo_run::TABLES.get(1).copied(),
        super::stereo_run::TABLES.get(2).copied(),
    ];
    let tables = blobs.map(|b| b.and_then(|b| DemTable::parse(b).ok()));
    let mut own = Aligned([0u8; CRAFT_LEN]);
    let mut rng = SplitMix64::new(0xc057_5c05_7500_0005);
    let mut hash = Fnv1a::new();
    for step in 0..COSTS_STEPS {
        if step % 64 == 1 {
            let bf = rng.below(16) as u8;
            let wf = rng.below(u64::from(bf) + 1) as u8;
            let (kind, fixed) = (rng.below(3), rng.range(-32768, 32767) as i16);
            let _ = craft(&mut own.0, wf, bf, || match kind {
                0 => fixed,
                1 => rng.range(-4, 4) as i16,
                _ => rng.range(-32768, 32767) as i16,
            });
        }
        let table = if step % 2 == 0 {
            tables.get(step / 2 % tables.len()).copied().flatten()
        } else {
            DemTable::parse(&own.0).ok()
        };
        let Some(table) = table else {
            continue;
        };
        let n = if step % 4 < 2 { 5 } else { 9 };
        let cands = (table.bias_bytes().len() / 2) as u64;
        let lo = rng.below(cands.saturating_sub(n as u64 - 1).max(1)) as usize;
        let bits = 1 + rng.below(48) as u32;
        let total = ((rng.next_u64() >> (64 - bits)) | 1 << (bits - 1)) as i64;
        let bound = total * (1 << 14) + (1 << 27);
        let signed = |rng: &mut SplitMix64, top: i64| {
            let v = (rng.next_u64() % (2 * top as u64 + 1)) as i64;
            v - top
        };
        let base = signed(&mut rng, bound);
        let spread = if step % 8 == 0 {
            0
        } else {
            bound.min(1 << (rng.below(62) as u32))
        };
        let mut raw = [0i64; 10];
        for r in raw.iter_mut().take(n) {
            *r = (base + signed(&mut rng, spread)).clamp(-bound, bound);
        }
        raw[n] = total;
        let mut out = [0u16; 9];
        let out = &mut out[..n];
        K::costs(&mut raw, total, &table, lo, out);
        for c in out.iter() {
            hash.write(&c.to_le_bytes());
        }
    }
    hash.finish()
}

/// `checksum costs-kernel STEPS 0x........` (compared host vs QEMU).
pub fn write_costs_kernel_check(out: &mut impl Write, sum: u32) -> fmt::Result {
    writeln!(out, "checksum costs-kernel {COSTS_STEPS} 0x{sum:08x}")
}
