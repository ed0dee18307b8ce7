//! Binocular cells (spec §3): per group `(level, carrier, shift)` the three
//! numbers `A = |z_L|² + |z_R(x − s)|²` and `X = z_L·conj z_R(x − s)` from
//! which the four phase-shifted complex cells follow exactly:
//! `C_Δφ = |z_L + e^{iΔφ} z_R(x − s)|² = A + 2(X_r cos Δφ + X_i sin Δφ)`.
//! The squared binocular sum is never formed (it overflows in fixed point).

use super::filters::Response;
use super::DemParams;

/// The phase shifts Δφ, in quarter turns: 0, π/2, π, 3π/2.
pub const PHASES: usize = 4;

/// One group of binocular cells: a level, a carrier and a position shift.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Group {
    /// Pyramid level (effective λ = λ·2^level).
    pub level: usize,
    /// Carrier index (see [`super::filters::carrier_deg`]).
    pub carrier: usize,
    /// Position shift in pixels of the level.
    pub shift_level: usize,
    /// The same shift in full-resolution pixels.
    pub shift: usize,
}

/// Shifts at `level`: `0, step, 2·step, ...` level px, enough to cover
/// `0..=max_disp` full-resolution px.
pub fn shifts(params: &DemParams, level: usize) -> usize {
    let step = usize::from(params.shift_step) << level;
    (usize::from(params.max_disp) + 1).div_ceil(step.max(1))
}

/// Every group, level-major, then carrier, then shift: the table's order.
pub fn groups(params: &DemParams) -> Vec<Group> {
    let mut out = Vec::new();
    for level in 0..usize::from(params.levels) {
        for carrier in 0..usize::from(params.carriers) {
            for k in 0..shifts(params, level) {
                let shift_level = k * usize::from(params.shift_step);
                out.push(Group {
                    level,
                    carrier,
                    shift_level,
                    shift: shift_level << level,
                });
            }
        }
    }
    out
}

/// `[A, X_r, X_i]` of one group.
pub type Energy = [f32; 3];

/// The energies of one group on its level's grid, summed over the input
/// channels (dem-spec §6; one channel: grey); `z_R` is 0 outside.
pub fn energies_level(left: &Response, right: &Response, shift: usize) -> Vec<Energy> {
    let (w, h) = (left.width, left.height);
    let mut out = vec![[0.0; 3]; w * h];
    for c in 0..left.channels.min(right.channels) {
        let plane = &left.z[c * w * h..(c + 1) * w * h];
        for y in 0..h {
            for x in 0..w {
                let l = plane[y * w + x];
                let r = right.at(c, x as isize - shift as isize, y);
                let e = [
                    l[0] * l[0] + l[1] * l[1] + r[0] * r[0] + r[1] * r[1],
                    l[0] * r[0] + l[1] * r[1],
                    l[1] * r[0] - l[0] * r[1],
                ];
                let dst = &mut out[y * w + x];
                if c == 0 {
                    // Assigned, not added: grey stays bit-identical.
                    *dst = e;
                } else {
                    for (d, v) in dst.iter_mut().zip(e) {
                        *d += v;
                    }
                }
            }
        }
    }
    out
}

/// Bilinear ×2^level upsampling of a level map to `width` x `height`:
/// full-resolution pixel `x` reads level coordinate `x / 2^level`.
pub fn upsample(
    map: &[Energy],
    lw: usize,
    lh: usize,
    level: usize,
    width: usize,
    height: usize,
) -> Vec<Energy> {
    if level == 0 {
        return map.to_vec();
    }
    let f = (1usize << level) as f32;
    let taps = |v: usize, n: usize| {
        let u = v as f32 / f;
        let i0 = (u.floor() as usize).min(n - 1);
        let i1 = (i0 + 1).min(n - 1);
        (i0, i1, u - i0 as f32)
    };
    let xs: Vec<_> = (0..width).map(|x| taps(x, lw)).collect();
    let mut out = vec![[0.0; 3]; width * height];
    for y in 0..height {
        let (y0, y1, fy) = taps(y, lh);
        for (x, &(x0, x1, fx)) in xs.iter().enumerate() {
            let p = |xx: usize, yy: usize| map[yy * lw + xx];
            let (a, b, c, d) = (p(x0, y0), p(x1, y0), p(x0, y1), p(x1, y1));
            let mut e = [0.0; 3];
            for i in 0..3 {
                let top = a[i] + fx * (b[i] - a[i]);
                let bottom = c[i] + fx * (d[i] - c[i]);
                e[i] = top + fy * (bottom - top);
            }
            out[y * width + x] = e;
        }
    }
    out
}

/// The energies of `group` at full resolution, from both eyes' monocular
/// responses (`[level][carrier]`).
pub fn energies(
    left: &[Vec<Response>],
    right: &[Vec<Response>],
    group: &Group,
    width: usize,
    height: usize,
) -> Vec<Energy> {
    let (l, r) = (
        &left[group.level][group.carrier],
        &right[group.level][group.carrier],
    );
    let e = energies_level(l, r, group.shift_level);
    upsample(&e, l.width, l.height, group.level, width, height)
}

/// The four complex-cell responses of one group from its energies, phase
/// shifts 0, π/2, π, 3π/2.
pub fn cells(e: Energy) -> [f32; PHASES] {
    [
        e[0] + 2.0 * e[1],
        e[0] + 2.0 * e[2],
        e[0] - 2.0 * e[1],
        e[0] - 2.0 * e[2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cells_equal_the_squared_binocular_sums() {
        let (l, r) = ([3.0f32, -1.5], [0.5f32, 2.0]);
        let left = Response {
            width: 1,
            height: 1,
            channels: 1,
            z: vec![l],
        };
        let right = Response {
            width: 1,
            height: 1,
            channels: 1,
            z: vec![r],
        };
        let e = energies_level(&left, &right, 0)[0];
        for (k, c) in cells(e).iter().enumerate() {
            let phi = k as f32 * core::f32::consts::FRAC_PI_2;
            let rot = [
                r[0] * phi.cos() - r[1] * phi.sin(),
                r[0] * phi.sin() + r[1] * phi.cos(),
            ];
            let direct = (l[0] + rot[0]).powi(2) + (l[1] + rot[1]).powi(2);
            assert!((c - direct).abs() < 1e-4, "{k}: {c} vs {direct}");
        }
    }

    #[test]
    fn stacked_channels_sum_their_energies() {
        // Two channels, 3x1, shift 1: the stacked energies are the sums of
        // the single-channel ones (exactly: one f32 addition of each).
        let z = |s: f32| -> Vec<[f32; 2]> { (0..3).map(|i| [s * i as f32, 1.0 - s]).collect() };
        let one = |z: Vec<[f32; 2]>| Response {
            width: 3,
            height: 1,
            channels: 1,
            z,
        };
        let (l0, l1, r0, r1) = (one(z(0.5)), one(z(-2.0)), one(z(1.5)), one(z(3.0)));
        let both = |a: &Response, b: &Response| Response::stack(vec![a.clone(), b.clone()]);
        let sum = energies_level(&both(&l0, &l1), &both(&r0, &r1), 1);
        let (e0, e1) = (energies_level(&l0, &r0, 1), energies_level(&l1, &r1, 1));
        for ((s, a), b) in sum.iter().zip(&e0).zip(&e1) {
            for i in 0..3 {
                assert_eq!(s[i], a[i] + b[i]);
            }
        }
        assert!(sum.iter().any(|e| e[1] != 0.0));
    }

    #[test]
    fn default_population_has_the_spec_size() {
        let p = DemParams {
            max_disp: 15,
            ..DemParams::default()
        };
        // 3 carriers x (8 + 4) shifts.
        assert_eq!(groups(&p).len(), 36);
        assert_eq!(groups(&p).last().unwrap().shift, 12);
    }
}
