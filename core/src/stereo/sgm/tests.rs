// Index loops read most plainly in this small reference.
#![allow(clippy::needless_range_loop)]
use super::*;
use crate::rng::SplitMix64;

const W: usize = 10;
const H: usize = 6;
const NMAX: usize = 12;
const D: usize = 40;
/// `+∞` of the naive reference.
const BIG: u64 = 1 << 40;

/// A random volume: dimensions, penalties, windows and costs.
struct Volume {
    w: usize,
    h: usize,
    n: usize,
    p1: u16,
    p2: u16,
    lo: [[u16; W]; H],
    c: [[[u16; NMAX]; W]; H],
}

fn volume(rng: &mut SplitMix64, n: usize) -> Volume {
    let (w, h) = (
        1 + rng.below(W as u64) as usize,
        1 + rng.below(H as u64) as usize,
    );
    let p2 = match rng.below(4) {
        0 => rng.below(30_000) as u16,
        1 => u16::MAX - rng.below(3) as u16,
        _ => rng.below(65) as u16,
    };
    let p1 = rng.below(u64::from(p2) + 1) as u16;
    let max = u16::MAX - p2;
    // Windows up to 20 apart (offsets far beyond ±(n + 1)), often equal
    // to a neighbour's (offset 0), sometimes 0.
    let top = (D - n) as u64;
    let spread = 1 + rng.below(top.min(20) + 1);
    let mut lo = [[0u16; W]; H];
    for y in 0..h {
        for x in 0..w {
            lo[y][x] = match rng.below(6) {
                0 if y > 0 => lo[y - 1][x],
                1 if x > 0 => lo[y][x - 1],
                2 if y > 0 && x + 1 < w => lo[y - 1][x + 1],
                3 => 0,
                _ => rng.below(spread) as u16,
            };
        }
    }
    let mut c = [[[0u16; NMAX]; W]; H];
    let big = rng.below(3) == 0;
    for v in c.iter_mut().flatten().flatten() {
        *v = if big {
            max - rng.below(u64::from(max.min(300)) + 1) as u16
        } else {
            rng.below(u64::from(max.min(255)) + 1) as u16
        };
    }
    Volume {
        w,
        h,
        n,
        p1,
        p2,
        lo,
        c,
    }
}

/// The module docs' recurrence over the full range `0..D`, `+∞` outside
/// each pixel's window, path by path: the sums at each pixel's window.
fn naive(v: &Volume) -> [[[u64; NMAX]; W]; H] {
    let cost = |x: usize, y: usize, d: usize| {
        let l = usize::from(v.lo[y][x]);
        (l..l + v.n)
            .contains(&d)
            .then(|| u64::from(v.c[y][x][d - l]))
    };
    let (p1, p2) = (u64::from(v.p1), u64::from(v.p2));
    let mut sums = [[[0u64; NMAX]; W]; H];
    for (dx, dy) in [(1i32, 0i32), (-1, 0), (0, 1), (1, 1), (-1, 1)] {
        let mut l = [[[BIG; D]; W]; H];
        for y in 0..v.h {
            let xs: [usize; W] =
                core::array::from_fn(|i| if dx < 0 { v.w.saturating_sub(1 + i) } else { i });
            for &x in xs.iter().take(v.w) {
                let (px, py) = (x as i32 - dx, y as i32 - dy);
                let pred = (px >= 0 && py >= 0 && (px as usize) < v.w)
                    .then(|| l[py as usize][px as usize]);
                for d in 0..D {
                    let Some(cd) = cost(x, y, d) else { continue };
                    l[y][x][d] = match pred {
                        None => cd,
                        Some(p) => {
                            let min = *p.iter().min().unwrap();
                            let at =
                                |j: i64| usize::try_from(j).ok().and_then(|j| p.get(j)).copied();
                            let near = [at(d as i64 - 1), at(d as i64 + 1)]
                                .into_iter()
                                .flatten()
                                .min()
                                .unwrap_or(BIG);
                            let here = at(d as i64).unwrap_or(BIG);
                            cd + here.min(near + p1).min(min + p2) - min
                        }
                    };
                    assert!(l[y][x][d] <= u64::from(u16::MAX));
                    let i = d - usize::from(v.lo[y][x]);
                    sums[y][x][i] += l[y][x][d];
                }
            }
        }
    }
    sums
}

/// Runs `frames` frames of `v` through one `Sgm` (reset between) and
/// checks each against [`naive`].
fn check(v: &Volume, frames: usize) {
    check_with::<SafePhase>(v, frames);
}

/// Steps the [`Lanes`] kernel took.
static LANE_STEPS: core::sync::atomic::AtomicUsize = core::sync::atomic::AtomicUsize::new(0);

/// The firmware's assembly step (`firmware-sim/src/dsp/sgm.rs`) written
/// plainly: 16-bit lanes, `min(h(d ± 1)) + P1` saturating at 65535,
/// the pads as `min(pad, 65535)`.
struct Lanes;

impl PhaseKernel for Lanes {
    fn sgm_step5(
        c: &[u16; 5],
        p: &[u16; 5],
        pad: u32,
        pen: (u32, u32),
        acc: &mut [u32; 5],
    ) -> [u16; 5] {
        lanes(c, p, pad, pen, acc)
    }
    fn sgm_step9(
        c: &[u16; 9],
        p: &[u16; 9],
        pad: u32,
        pen: (u32, u32),
        acc: &mut [u32; 9],
    ) -> [u16; 9] {
        lanes(c, p, pad, pen, acc)
    }
}

/// [`Lanes`]' step for `N` candidates.
fn lanes<const N: usize>(
    c: &[u16; N],
    p: &[u16; N],
    pad: u32,
    (p1, p2): (u32, u32),
    acc: &mut [u32; N],
) -> [u16; N] {
    LANE_STEPS.fetch_add(1, core::sync::atomic::Ordering::Relaxed);
    let pad16 = pad.min(0xffff) as u16;
    let h = |j: usize| p.get(j).copied().unwrap_or(pad16);
    let (p1, p2) = (p1 as u16, p2 as u16);
    let l: [u16; N] = core::array::from_fn(|d| {
        let near = h(d.wrapping_sub(1)).min(h(d + 1)).saturating_add(p1);
        c[d].wrapping_add(near.min(p[d]).min(p2))
    });
    let min = l.iter().copied().min().unwrap();
    for (a, &v) in acc.iter_mut().zip(&l) {
        *a += u32::from(v);
    }
    l.map(|v| v - min)
}

#[test]
fn a_lane_kernel_gives_the_naive_recurrence() {
    let mut rng = SplitMix64::new(0x1a9e5);
    for n in [5, 9] {
        for _ in 0..300 {
            let v = volume(&mut rng, n);
            check_with::<Lanes>(&v, 2);
        }
    }
    // The kernel took the steps whose windows start together.
    assert!(LANE_STEPS.load(core::sync::atomic::Ordering::Relaxed) > 2000);
}

/// [`check`] with the windows-of-5 step of kernel `K`.
fn check_with<K: PhaseKernel>(v: &Volume, frames: usize) {
    let want = naive(v);
    let (w, n) = (v.w, v.n);
    let mut scratch = [0xffffu16; scratch_len(W, NMAX)];
    let scratch = &mut scratch[..scratch_len(w, n)];
    let mut sgm = Sgm::new(w, n, v.p1, v.p2, scratch).unwrap();
    for _ in 0..frames {
        sgm.reset();
        for y in 0..v.h {
            let mut costs = [0u16; W * NMAX];
            for (dst, src) in costs.chunks_exact_mut(n).zip(&v.c[y][..w]) {
                dst.copy_from_slice(&src[..n]);
            }
            let mut out = [0u32; W * NMAX];
            sgm.push_row_with::<K>(&costs[..w * n], &v.lo[y][..w], &mut out[..w * n])
                .unwrap();
            for (x, o) in out[..w * n].chunks_exact(n).enumerate() {
                for (i, &s) in o.iter().enumerate() {
                    assert_eq!(
                        u64::from(s),
                        want[y][x][i],
                        "n {n} {w}x{} p1 {} p2 {} at ({x}, {y}) candidate {i}",
                        v.h,
                        v.p1,
                        v.p2
                    );
                }
            }
        }
    }
}

#[test]
fn rows_equal_the_naive_recurrence() {
    let mut rng = SplitMix64::new(0x005e_6a57);
    // 5 (the engine's fine levels), 9 (its coarsest), others fast (up
    // to 9) and generic (10 and up).
    for n in [5, 9, 1, 2, 3, 4, 6, 7, 8, 10, 12] {
        for _ in 0..300 {
            let v = volume(&mut rng, n);
            check(&v, 2);
        }
    }
}
