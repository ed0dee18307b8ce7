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

use ndarray::{Array1, Array2, ArrayView2, Axis, Zip};

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
        let y = self.predict(x);
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
