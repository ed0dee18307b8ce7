//! Monocular front end: grey input, the ↓2 binomial pyramid and the complex
//! Gabor bank (spec §2).
//!
//! A kernel is `g(q) = G_σ(q)·exp(i 2π q·n_θ / λ)` with an isotropic
//! envelope normalised to Σ = 1, so it factors into a y pass and an x pass
//! of complex 1-D kernels. Zero DC is `g − env·Σg`: the response is the
//! separable complex response minus `Σg` times the envelope-blurred image,
//! both separable, which is what the fixed-point port will run. Filtering is
//! a correlation, `z(x) = Σ_t g(t)·I(x + t)`, with replicated borders.

use super::DemParams;
use protogist::image::{ImageView, Rgb8};

/// A complex value `(re, im)`.
pub type Complex = [f32; 2];

/// A grey plane, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Plane {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Values.
    pub data: Vec<f32>,
}

impl Plane {
    /// The value at `(x, y)` with clamped coordinates.
    pub fn at(&self, x: isize, y: isize) -> f32 {
        let cx = x.clamp(0, self.width as isize - 1) as usize;
        let cy = y.clamp(0, self.height as isize - 1) as usize;
        self.data[cy * self.width + cx]
    }
}

/// Grey (Rec. 601 luma, 0..255) of an RGB image.
pub fn grey(img: &ImageView<'_, Rgb8>) -> Plane {
    let (width, height) = img.size();
    let data = img
        .pixels()
        .map(|p| {
            (299.0 * f32::from(p.r) + 587.0 * f32::from(p.g) + 114.0 * f32::from(p.b)) / 1000.0
        })
        .collect();
    Plane {
        width,
        height,
        data,
    }
}

/// One ↓2 step: binomial `[1 4 6 4 1]/16` in x and y, then every second
/// pixel; coarse pixel `i` sits on fine pixel `2i`.
pub fn pyramid_down(src: &Plane) -> Plane {
    const B: [f32; 5] = [1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0];
    let (w, h) = (src.width.div_ceil(2), src.height.div_ceil(2));
    // x pass on every source row, at the kept columns only.
    let mut tmp = vec![0.0f32; w * src.height];
    for y in 0..src.height {
        for i in 0..w {
            let x = 2 * i as isize;
            tmp[y * w + i] = (-2..=2)
                .map(|t| B[(t + 2) as usize] * src.at(x + t, y as isize))
                .sum();
        }
    }
    let tmp = Plane {
        width: w,
        height: src.height,
        data: tmp,
    };
    let mut data = vec![0.0f32; w * h];
    for j in 0..h {
        for i in 0..w {
            let y = 2 * j as isize;
            data[j * w + i] = (-2..=2)
                .map(|t| B[(t + 2) as usize] * tmp.at(i as isize, y + t))
                .sum();
        }
    }
    Plane {
        width: w,
        height: h,
        data,
    }
}

/// The pyramid: level 0 is the input, level `l` is `l` ↓2 steps down.
pub fn pyramid(base: Plane, levels: usize) -> Vec<Plane> {
    let mut out = vec![base];
    while out.len() < levels {
        let next = pyramid_down(&out[out.len() - 1]);
        out.push(next);
    }
    out
}

/// Carrier direction `k` of `n`, degrees from horizontal: evenly spread
/// over (−90°, 90°) around 0, e.g. −45, 0, 45 for 3.
pub fn carrier_deg(k: usize, n: usize) -> f32 {
    (k as f32 - (n as f32 - 1.0) / 2.0) * 180.0 / (n as f32 + 1.0)
}

/// One separable Gabor kernel: the two 1-D complex kernels, the envelope
/// (Σ = 1 over 2-D) and the 2-D sum Σg used for DC removal.
#[derive(Clone, Debug, PartialEq)]
pub struct Gabor {
    /// x kernel, taps `-r..=r`.
    pub kx: Vec<Complex>,
    /// y kernel.
    pub ky: Vec<Complex>,
    /// 1-D envelope, Σ = 1.
    pub env: Vec<f32>,
    /// Σ over the 2-D kernel (complex).
    pub dc: Complex,
}

/// The kernel of carrier `theta_deg` for `params` (λ, σ/λ, radius).
pub fn gabor(params: &DemParams, theta_deg: f32) -> Gabor {
    let lambda = params.wavelength;
    let sigma = params.sigma_per_wavelength * lambda;
    let r = isize::from(params.radius);
    let raw: Vec<f32> = (-r..=r)
        .map(|t| (-(t * t) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let total: f32 = raw.iter().sum();
    let env: Vec<f32> = raw.iter().map(|v| v / total).collect();
    let th = theta_deg.to_radians();
    let (kx, ky) = (
        core::f32::consts::TAU * th.cos() / lambda,
        core::f32::consts::TAU * th.sin() / lambda,
    );
    let modulate = |k: f32| -> Vec<Complex> {
        (-r..=r)
            .zip(&env)
            .map(|(t, &e)| [e * (k * t as f32).cos(), e * (k * t as f32).sin()])
            .collect()
    };
    let (kx, ky) = (modulate(kx), modulate(ky));
    let sum = |k: &[Complex]| k.iter().fold([0.0, 0.0], |a, c| [a[0] + c[0], a[1] + c[1]]);
    let (sx, sy) = (sum(&kx), sum(&ky));
    Gabor {
        kx,
        ky,
        env,
        dc: mul(sx, sy),
    }
}

/// Complex product.
pub fn mul(a: Complex, b: Complex) -> Complex {
    [a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0]]
}

/// A complex response map of one or more input channels (one, grey, in
/// every path of the product).
#[derive(Clone, Debug, PartialEq)]
pub struct Response {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Channels stacked in `z`, at least 1.
    pub channels: usize,
    /// `z` per channel and pixel, channel-major planes of `width·height`.
    pub z: Vec<Complex>,
}

impl Response {
    /// `z` of channel `c` at `(x, y)`, or 0 outside the map.
    pub fn at(&self, c: usize, x: isize, y: usize) -> Complex {
        if x < 0 || x as usize >= self.width {
            [0.0, 0.0]
        } else {
            self.z[(c * self.height + y) * self.width + x as usize]
        }
    }

    /// The channels of `parts` (all of one size, at least one) stacked.
    pub fn stack(parts: Vec<Response>) -> Response {
        let (width, height) = parts.first().map_or((0, 0), |p| (p.width, p.height));
        debug_assert!(parts.iter().all(|p| (p.width, p.height) == (width, height)));
        Response {
            width,
            height,
            channels: parts.iter().map(|p| p.channels).sum(),
            z: parts.into_iter().flat_map(|p| p.z).collect(),
        }
    }
}

/// The zero-DC complex response of `img` to `g`: y pass, then x pass.
pub fn respond(img: &Plane, g: &Gabor) -> Response {
    let (w, h) = (img.width, img.height);
    let r = (g.kx.len() / 2) as isize;
    // y pass: complex (Gabor) and real (envelope), both on the grey input.
    let mut col = vec![[0.0f32; 3]; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0.0f32; 3];
            for t in -r..=r {
                let v = img.at(x as isize, y as isize + t);
                let k = g.ky[(t + r) as usize];
                acc[0] += k[0] * v;
                acc[1] += k[1] * v;
                acc[2] += g.env[(t + r) as usize] * v;
            }
            col[y * w + x] = acc;
        }
    }
    let mut z = vec![[0.0f32; 2]; w * h];
    for y in 0..h {
        let row = &col[y * w..(y + 1) * w];
        for x in 0..w {
            let mut acc = [0.0f32; 3];
            for t in -r..=r {
                let v = row[(x as isize + t).clamp(0, w as isize - 1) as usize];
                let k = g.kx[(t + r) as usize];
                let c = mul(k, [v[0], v[1]]);
                acc[0] += c[0];
                acc[1] += c[1];
                acc[2] += g.env[(t + r) as usize] * v[2];
            }
            z[y * w + x] = [acc[0] - g.dc[0] * acc[2], acc[1] - g.dc[1] * acc[2]];
        }
    }
    Response {
        width: w,
        height: h,
        channels: 1,
        z,
    }
}

/// Monocular responses of one eye, computed once: `[level][carrier]`.
pub fn monocular(params: &DemParams, img: Plane) -> Vec<Vec<Response>> {
    monocular_planes(params, vec![img])
}

/// Monocular responses of one eye with one or more input channels (all of
/// one size), each filtered by the same bank: `[level][carrier]`, the
/// channels stacked in each [`Response`].
pub fn monocular_planes(params: &DemParams, planes: Vec<Plane>) -> Vec<Vec<Response>> {
    let n = usize::from(params.carriers);
    let levels = usize::from(params.levels);
    let bank: Vec<Gabor> = (0..n).map(|k| gabor(params, carrier_deg(k, n))).collect();
    let pyramids: Vec<Vec<Plane>> = planes.into_iter().map(|p| pyramid(p, levels)).collect();
    (0..levels)
        .map(|l| {
            bank.iter()
                .map(|g| Response::stack(pyramids.iter().map(|p| respond(&p[l], g)).collect()))
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_have_zero_dc_and_the_default_carriers() {
        let p = DemParams::default();
        assert_eq!(
            (0..3).map(|k| carrier_deg(k, 3)).collect::<Vec<_>>(),
            [-45.0, 0.0, 45.0]
        );
        let flat = Plane {
            width: 20,
            height: 20,
            data: vec![87.0; 400],
        };
        for k in 0..3 {
            let z = respond(&flat, &gabor(&p, carrier_deg(k, 3)));
            assert!(z.z.iter().all(|c| c[0].abs() < 1e-3 && c[1].abs() < 1e-3));
        }
    }

    #[test]
    fn a_horizontal_grating_at_the_carrier_gives_a_steady_magnitude() {
        let p = DemParams::default();
        let (w, h) = (40, 24);
        let data = (0..w * h)
            .map(|i| 128.0 + 100.0 * (core::f32::consts::TAU * (i % w) as f32 / 4.0).cos())
            .collect();
        let img = Plane {
            width: w,
            height: h,
            data,
        };
        let z = respond(&img, &gabor(&p, 0.0));
        let m = |x: usize| z.z[12 * w + x][0].hypot(z.z[12 * w + x][1]);
        assert!(
            (m(20) - m(21)).abs() < 0.01 * m(20) && m(20) > 40.0,
            "{}",
            m(20)
        );
    }
}
