//! Training the decoding population on random-dot stereograms (spec §4).
//!
//! For each integer disparity `d` in `0..=max_disp`, `train_images` RDS
//! pairs (50 % density, 1-px dots of 0/255, right = left shifted by `d`)
//! are run through the population; `W_j(d)` is the mean response of cell
//! `j` over the interior pixels, floored at 10⁻³·max W. The decoder keeps
//! `ℓ_j(d) = ln W_j(d) − mean_d ln W_j(d)` folded per group into
//! `(a, b, c)` (so that `Σ_φ C_φ ℓ_φ = A·a + X_r·b + X_i·c`) and
//! `ΣW(d) / mean_d ΣW(d)`. Everything is seeded and deterministic.

use super::filters::{monocular, Plane};
use super::population::{cells, energies, groups, Energy, PHASES};
use super::{DemLayout, DemParams};
use protogist::rng::SplitMix64;

/// The trained read-out: folded log-templates and the normalised ΣW(d).
#[derive(Clone, Debug, PartialEq)]
pub struct Decoder {
    /// The population it was trained for.
    pub layout: DemLayout,
    /// `[group][d]` → `[a, b, c]`, group-major.
    pub weights: Vec<[f32; 3]>,
    /// `ΣW(d) / mean_d ΣW(d)`, one per disparity.
    pub bias: Vec<f32>,
}

impl Decoder {
    /// Number of disparities, `max_disp + 1`.
    pub fn disparities(&self) -> usize {
        self.bias.len()
    }

    /// The weights of group `g`, one `[a, b, c]` per disparity.
    pub fn group(&self, g: usize) -> &[[f32; 3]] {
        let n = self.disparities();
        &self.weights[g * n..(g + 1) * n]
    }
}

/// A random-dot stereogram of uniform disparity `d`: 50 % of the 1-px dots
/// are 255, the rest 0, and `right(x) = left(x + d)`.
pub fn random_dot_pair(width: usize, height: usize, d: usize, seed: u64) -> (Plane, Plane) {
    let mut rng = SplitMix64::new(seed);
    let wide = width + d;
    let field: Vec<f32> = (0..wide * height)
        .map(|_| {
            if rng.next_u64() >> 63 == 1 {
                255.0
            } else {
                0.0
            }
        })
        .collect();
    let cut = |off: usize| Plane {
        width,
        height,
        data: (0..height)
            .flat_map(|y| {
                field[y * wide + off..y * wide + off + width]
                    .iter()
                    .copied()
            })
            .collect(),
    };
    (cut(0), cut(d))
}

/// Pixels kept clear of the training images' borders: pyramid blur and
/// Gabor support at the coarsest level.
pub fn train_margin(params: &DemParams) -> usize {
    (usize::from(params.radius) + 3) << usize::from(params.levels.max(1) - 1)
}

/// The seed of training image `i` at disparity `d`.
fn image_seed(seed: u64, d: usize, i: usize) -> u64 {
    seed ^ ((d as u64) << 32 | i as u64).wrapping_mul(0xd1b5_4a32_d192_ed03)
}

/// Mean `[A, X_r, X_i]` per group over the interior of the RDS at `d`.
fn mean_energies(params: &DemParams, d: usize) -> Vec<Energy> {
    let m = train_margin(params);
    let dmax = usize::from(params.max_disp);
    let (tw, th) = (
        usize::from(params.train_width),
        usize::from(params.train_height),
    );
    let (w, h) = (tw + dmax + 2 * m, th + 2 * m);
    let gs = groups(params);
    let mut sums = vec![[0.0f64; 3]; gs.len()];
    for i in 0..usize::from(params.train_images) {
        let (l, r) = random_dot_pair(w, h, d, image_seed(params.train_seed, d, i));
        let (ml, mr) = (monocular(params, l), monocular(params, r));
        for (g, sum) in gs.iter().zip(&mut sums) {
            let e = energies(&ml, &mr, g, w, h);
            for y in m..m + th {
                for x in m + dmax..m + dmax + tw {
                    for (s, v) in sum.iter_mut().zip(e[y * w + x]) {
                        *s += f64::from(v);
                    }
                }
            }
        }
    }
    let n = (tw * th * usize::from(params.train_images)).max(1) as f64;
    sums.iter().map(|s| s.map(|v| (v / n) as f32)).collect()
}

/// Trains the decoder for `params`; disparities are spread over the
/// available cores (the result does not depend on how many).
pub fn train(params: &DemParams) -> Decoder {
    let n_disp = usize::from(params.max_disp) + 1;
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(n_disp);
    let mut means: Vec<Vec<Energy>> = vec![Vec::new(); n_disp];
    std::thread::scope(|s| {
        for (t, chunk) in means.chunks_mut(n_disp.div_ceil(threads)).enumerate() {
            let first = t * n_disp.div_ceil(threads);
            s.spawn(move || {
                for (k, slot) in chunk.iter_mut().enumerate() {
                    *slot = mean_energies(params, first + k);
                }
            });
        }
    });
    fold(params, &means)
}

/// The decoder from the mean energies `[d][group]`.
pub fn fold(params: &DemParams, means: &[Vec<Energy>]) -> Decoder {
    let n_disp = means.len();
    let n_groups = means.first().map_or(0, Vec::len);
    // W[d][group][phase]
    let w: Vec<Vec<[f32; PHASES]>> = means
        .iter()
        .map(|g| g.iter().map(|&e| cells(e)).collect())
        .collect();
    let max = w.iter().flatten().flatten().fold(0.0f32, |m, &v| m.max(v));
    let floor = (1e-3 * max).max(f32::MIN_POSITIVE);
    let ln = |v: f32| v.max(floor).ln();
    let mut weights = vec![[0.0f32; 3]; n_groups * n_disp];
    #[allow(clippy::needless_range_loop)] // w is [d][group][phase]
    for g in 0..n_groups {
        for p in 0..PHASES {
            let mean = (0..n_disp).map(|d| ln(w[d][g][p])).sum::<f32>() / n_disp as f32;
            for d in 0..n_disp {
                let l = ln(w[d][g][p]) - mean;
                let abc = &mut weights[g * n_disp + d];
                abc[0] += l;
                // b = 2(ℓ_0 − ℓ_π), c = 2(ℓ_π/2 − ℓ_3π/2).
                match p {
                    0 => abc[1] += 2.0 * l,
                    1 => abc[2] += 2.0 * l,
                    2 => abc[1] -= 2.0 * l,
                    _ => abc[2] -= 2.0 * l,
                }
            }
        }
    }
    let sum_w: Vec<f32> = w
        .iter()
        .map(|g| g.iter().flatten().map(|&v| v.max(floor)).sum())
        .collect();
    let mean_sum = sum_w.iter().sum::<f32>() / n_disp.max(1) as f32;
    Decoder {
        layout: super::layout_of(params),
        weights,
        bias: sum_w.iter().map(|s| s / mean_sum).collect(),
    }
}
