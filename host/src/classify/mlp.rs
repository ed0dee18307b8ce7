//! The float network of the paper's section 4.4: two layers, feed-forward,
//! log-sigmoid hidden and output units, one output per class.
//!
//! `Y = σ(σ(X W1ᵀ + b1) W2ᵀ + b2)` for a batch `X` of row vectors
//! (`n × d`), with `W1: H × d`, `W2: N × H`. Products go through
//! `ndarray`'s `dot` (the `matrixmultiply` GEMM, threaded).
//!
//! **Performance.** `MSE_REG = γ·MSE + (1 − γ)·MSW` with
//! `MSE = Σ (y − t)² / (n·N)` over all outputs of the batch and
//! `MSW = Σ w² / P` over all `P` weights *and biases* of both layers, as
//! MATLAB's `msereg` (whose `ratio` parameter is the `γ` here; the paper's
//! `γ = 0.2` is [`GAMMA`]). Note that newer MATLAB's
//! `mse(..., 'regularization', r)` weighs the other way round,
//! `(1 − r)·MSE + r·MSW`; the paper's wording ("mean-squared normalised
//! error with a regularisation factor γ = 0.2") does not settle which one
//! was meant, so `γ` is a parameter.

use ndarray::linalg::general_mat_mul;
use ndarray::{s, Array1, Array2, ArrayView2, Axis, Zip};

/// Rows per block of [`Mlp::gradient_blocked`] and [`Mlp::predict_blocked`]:
/// their working memory is `BLOCK_ROWS × (H + N)` values whatever the
/// number of rows.
pub const BLOCK_ROWS: usize = 1024;

/// The paper's regularisation factor (weight of the MSE term).
pub const GAMMA: f64 = 0.2;

/// The network's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Mlp {
    /// Hidden weights, `H × d`.
    pub w1: Array2<f64>,
    /// Hidden biases, `H`.
    pub b1: Array1<f64>,
    /// Output weights, `N × H`.
    pub w2: Array2<f64>,
    /// Output biases, `N`.
    pub b2: Array1<f64>,
}

/// Gradients (or any per-parameter quantity) shaped like an [`Mlp`].
pub type Grads = Mlp;

/// The project's seeded generator (re-exported for the host's users).
pub use protogist::rng::SplitMix64 as SplitMix;

/// Uniform in `[0, 1)` from 53 random bits.
pub fn unit(rng: &mut SplitMix) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// The logistic (log-sigmoid) function.
#[inline]
pub fn logsig(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

fn uniform(rng: &mut SplitMix, rows: usize, cols: usize, a: f64) -> Array2<f64> {
    Array2::from_shape_simple_fn((rows, cols), || a * (2.0 * unit(rng) - 1.0))
}

impl Mlp {
    /// A seeded network: weights and biases uniform in `±1/√fan_in`
    /// (fan-in `d` for the hidden layer, `H` for the output layer). MATLAB
    /// initialises with Nguyen–Widrow; this is the plain, reproducible
    /// choice.
    pub fn new(inputs: usize, hidden: usize, outputs: usize, seed: u64) -> Self {
        let mut rng = SplitMix::new(seed);
        let a1 = 1.0 / (inputs.max(1) as f64).sqrt();
        let a2 = 1.0 / (hidden.max(1) as f64).sqrt();
        let w1 = uniform(&mut rng, hidden, inputs, a1);
        let b1 = uniform(&mut rng, 1, hidden, a1).into_shape_with_order(hidden);
        let w2 = uniform(&mut rng, outputs, hidden, a2);
        let b2 = uniform(&mut rng, 1, outputs, a2).into_shape_with_order(outputs);
        Self {
            w1,
            b1: b1.expect("1 × H reshapes to H"),
            w2,
            b2: b2.expect("1 × N reshapes to N"),
        }
    }

    /// All zeros, shaped like `self`.
    pub fn zeros_like(&self) -> Self {
        Self {
            w1: Array2::zeros(self.w1.raw_dim()),
            b1: Array1::zeros(self.b1.raw_dim()),
            w2: Array2::zeros(self.w2.raw_dim()),
            b2: Array1::zeros(self.b2.raw_dim()),
        }
    }

    /// Input length `d`.
    pub fn inputs(&self) -> usize {
        self.w1.ncols()
    }

    /// Hidden units `H`.
    pub fn hidden(&self) -> usize {
        self.w1.nrows()
    }

    /// Outputs (classes) `N`.
    pub fn outputs(&self) -> usize {
        self.w2.nrows()
    }

    /// Number of parameters `P` (weights and biases).
    pub fn params(&self) -> usize {
        self.w1.len() + self.b1.len() + self.w2.len() + self.b2.len()
    }

    /// Hidden and output activations of a batch (`n × d`).
    pub fn forward(&self, x: ArrayView2<'_, f64>) -> (Array2<f64>, Array2<f64>) {
        let mut h = x.dot(&self.w1.t()) + &self.b1;
        h.par_mapv_inplace(logsig);
        let mut y = h.dot(&self.w2.t()) + &self.b2;
        y.par_mapv_inplace(logsig);
        (h, y)
    }

    /// Output activations of a batch (`n × N`).
    pub fn predict(&self, x: ArrayView2<'_, f64>) -> Array2<f64> {
        self.forward(x).1
    }

    /// [`Mlp::predict`] block by block ([`BLOCK_ROWS`] rows at a time).
    pub fn predict_blocked(&self, x: ArrayView2<'_, f64>) -> Array2<f64> {
        let n = x.nrows();
        if n <= BLOCK_ROWS {
            return self.predict(x);
        }
        let mut y = Array2::zeros((n, self.outputs()));
        for start in (0..n).step_by(BLOCK_ROWS) {
            let end = (start + BLOCK_ROWS).min(n);
            y.slice_mut(s![start..end, ..])
                .assign(&self.predict(x.slice(s![start..end, ..])));
        }
        y
    }

    /// [`Mlp::gradient`] accumulated over blocks of `block` rows, so the
    /// hidden activations and deltas take `block × H` values instead of
    /// `n × H`; the same as [`Mlp::gradient`] (bit for bit) when
    /// `n <= block`, else equal up to the order of the sums.
    pub fn gradient_blocked(
        &self,
        x: ArrayView2<'_, f64>,
        t: ArrayView2<'_, f64>,
        gamma: f64,
        block: usize,
    ) -> (f64, f64, Grads) {
        let n = x.nrows();
        if n <= block.max(1) {
            return self.gradient(x, t, gamma);
        }
        let mut g = self.zeros_like();
        let mut sq = 0.0;
        let scale = 2.0 * gamma / (n * self.outputs()).max(1) as f64;
        for start in (0..n).step_by(block.max(1)) {
            let end = (start + block).min(n);
            let xc = x.slice(s![start..end, ..]);
            let tc = t.slice(s![start..end, ..]);
            let (h, mut d2) = self.forward(xc);
            sq += Zip::from(&d2).and(&tc).par_fold(
                || 0.0,
                |a, &y, &t| a + (y - t) * (y - t),
                |a, b| a + b,
            );
            Zip::from(&mut d2)
                .and(&tc)
                .par_for_each(|y, &t| *y = scale * (*y - t) * *y * (1.0 - *y));
            let mut d1 = d2.dot(&self.w2);
            Zip::from(&mut d1)
                .and(&h)
                .par_for_each(|d, &h| *d *= h * (1.0 - h));
            general_mat_mul(1.0, &d1.t(), &xc, 1.0, &mut g.w1);
            g.b1 += &d1.sum_axis(Axis(0));
            general_mat_mul(1.0, &d2.t(), &h, 1.0, &mut g.w2);
            g.b2 += &d2.sum_axis(Axis(0));
        }
        let mse = sq / (n * self.outputs()).max(1) as f64;
        let msw = self.sum_sq() / self.params() as f64;
        let reg = 2.0 * (1.0 - gamma) / self.params() as f64;
        g.w1.scaled_add(reg, &self.w1);
        g.b1.scaled_add(reg, &self.b1);
        g.w2.scaled_add(reg, &self.w2);
        g.b2.scaled_add(reg, &self.b2);
        (gamma * mse + (1.0 - gamma) * msw, mse, g)
    }

    /// Floating-point operations of one [`Mlp::gradient`] over `n` rows
    /// (multiply and add counted apart): the forward products
    /// `2n(dH + HN)`, the backward ones `2n(HN + dH + NH)`.
    pub fn gradient_flops(&self, n: usize) -> f64 {
        let (d, h, k) = (
            self.inputs() as f64,
            self.hidden() as f64,
            self.outputs() as f64,
        );
        n as f64 * (4.0 * d * h + 6.0 * h * k)
    }

    /// `Σ w²` over all parameters.
    fn sum_sq(&self) -> f64 {
        let sq = |a: f64, &w: &f64| a + w * w;
        self.w1.fold(0.0, sq)
            + self.b1.fold(0.0, sq)
            + self.w2.fold(0.0, sq)
            + self.b2.fold(0.0, sq)
    }

    /// `(MSE_REG, MSE)` on a batch with targets `t` (`n × N`).
    pub fn perf(&self, x: ArrayView2<'_, f64>, t: ArrayView2<'_, f64>, gamma: f64) -> (f64, f64) {
        let y = self.predict_blocked(x);
        self.perf_of(&y, t, gamma)
    }

    fn perf_of(&self, y: &Array2<f64>, t: ArrayView2<'_, f64>, gamma: f64) -> (f64, f64) {
        let mse = (y - &t).mapv(|e| e * e).mean().unwrap_or(0.0);
        let msw = self.sum_sq() / self.params() as f64;
        (gamma * mse + (1.0 - gamma) * msw, mse)
    }

    /// `(MSE_REG, MSE)` and the gradient of `MSE_REG` with respect to every
    /// parameter, by backpropagation over the whole batch.
    pub fn gradient(
        &self,
        x: ArrayView2<'_, f64>,
        t: ArrayView2<'_, f64>,
        gamma: f64,
    ) -> (f64, f64, Grads) {
        let (h, y) = self.forward(x);
        let (perf, mse) = self.perf_of(&y, t, gamma);
        // d MSE_REG / d y = γ · 2 (y − t) / (n·N); through σ' = y (1 − y).
        let scale = 2.0 * gamma / y.len().max(1) as f64;
        let mut d2 = y;
        Zip::from(&mut d2)
            .and(&t)
            .par_for_each(|y, &t| *y = scale * (*y - t) * *y * (1.0 - *y));
        let mut d1 = d2.dot(&self.w2);
        Zip::from(&mut d1)
            .and(&h)
            .par_for_each(|d, &h| *d *= h * (1.0 - h));
        // d MSW / d w = 2 w / P.
        let reg = 2.0 * (1.0 - gamma) / self.params() as f64;
        let g = Grads {
            w1: d1.t().dot(&x) + &(reg * &self.w1),
            b1: d1.sum_axis(Axis(0)) + &(reg * &self.b1),
            w2: d2.t().dot(&h) + &(reg * &self.w2),
            b2: d2.sum_axis(Axis(0)) + &(reg * &self.b2),
        };
        (perf, mse, g)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::array;

    /// Central differences on every parameter of a 3-4-2 network.
    #[test]
    fn gradient_matches_finite_differences() {
        let net = Mlp::new(3, 4, 2, 7);
        let x = array![[0.5, -1.0, 2.0], [1.5, 0.2, -0.3], [-0.7, 0.9, 0.1]];
        let t = array![[1.0, 0.0], [0.0, 1.0], [1.0, 0.0]];
        for gamma in [GAMMA, 0.9, 1.0] {
            let (_, _, g) = net.gradient(x.view(), t.view(), gamma);
            let eps = 1e-6;
            let mut worst = 0f64;
            let mut check = |field: fn(&mut Mlp) -> &mut [f64], analytic: &[f64]| {
                for (i, &a) in analytic.iter().enumerate() {
                    let (mut p, mut m) = (net.clone(), net.clone());
                    field(&mut p)[i] += eps;
                    field(&mut m)[i] -= eps;
                    let num = (p.perf(x.view(), t.view(), gamma).0
                        - m.perf(x.view(), t.view(), gamma).0)
                        / (2.0 * eps);
                    let err = (num - a).abs() / (num.abs() + a.abs()).max(1e-8);
                    worst = worst.max(err);
                }
            };
            check(|n| n.w1.as_slice_mut().unwrap(), g.w1.as_slice().unwrap());
            check(|n| n.b1.as_slice_mut().unwrap(), g.b1.as_slice().unwrap());
            check(|n| n.w2.as_slice_mut().unwrap(), g.w2.as_slice().unwrap());
            check(|n| n.b2.as_slice_mut().unwrap(), g.b2.as_slice().unwrap());
            assert!(worst < 1e-5, "γ {gamma}: worst relative error {worst}");
        }
    }

    #[test]
    fn blocked_gradient_matches_the_whole_batch() {
        let net = Mlp::new(5, 7, 3, 2);
        let mut rng = SplitMix::new(5);
        let x = Array2::from_shape_simple_fn((23, 5), || unit(&mut rng) - 0.5);
        let t = Array2::from_shape_simple_fn((23, 3), || (unit(&mut rng) > 0.5) as u8 as f64);
        let (p, m, g) = net.gradient(x.view(), t.view(), GAMMA);
        for block in [1, 4, 10, 22] {
            let (pb, mb, gb) = net.gradient_blocked(x.view(), t.view(), GAMMA, block);
            assert!((p - pb).abs() < 1e-14 && (m - mb).abs() < 1e-14);
            for (a, b) in [(&g.w1, &gb.w1), (&g.w2, &gb.w2)] {
                assert!(
                    a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-14),
                    "{block}"
                );
            }
            assert!(g.b1.iter().zip(&gb.b1).all(|(a, b)| (a - b).abs() < 1e-14));
            assert!(g.b2.iter().zip(&gb.b2).all(|(a, b)| (a - b).abs() < 1e-14));
        }
        assert_eq!(net.gradient_blocked(x.view(), t.view(), GAMMA, 23).2, g);
    }

    #[test]
    fn perf_by_hand() {
        // All-zero parameters: outputs 0.5, MSW 0.
        let net = Mlp::new(2, 3, 2, 1).zeros_like();
        let x = array![[1.0, 2.0]];
        let t = array![[1.0, 0.0]];
        let (perf, mse) = net.perf(x.view(), t.view(), 0.2);
        assert!((mse - 0.25).abs() < 1e-15 && (perf - 0.05).abs() < 1e-15);
    }

    #[test]
    fn initialisation_is_seeded() {
        assert_eq!(Mlp::new(5, 3, 2, 9), Mlp::new(5, 3, 2, 9));
        assert_ne!(Mlp::new(5, 3, 2, 9), Mlp::new(5, 3, 2, 10));
        let n = Mlp::new(720, 8, 3, 0);
        assert_eq!((n.inputs(), n.hidden(), n.outputs()), (720, 8, 3));
        assert_eq!(n.params(), 720 * 8 + 8 + 8 * 3 + 3);
    }
}
