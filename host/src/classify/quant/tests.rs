//! Unit tests of `quant`.

use super::*;
use protogist::mlp::requant::{logsig_q12, logsig_u8};

#[test]
fn logsig_table_matches_its_definition() {
    assert_eq!(
        logsig_table(),
        protogist::mlp::logsig_table::LOGSIG_Q8.to_vec()
    );
}

/// Every Q12 input in [−2^16, 2^16] (|z| <= 16; beyond, σ is monotone
/// and both the table and the exact value are within 0.02 LSB of the
/// ends): at most 1 LSB of `65535 σ` and 0.51 LSB of `255 σ`.
#[test]
fn logsig_lut_within_one_lsb() {
    let (mut worst16, mut worst8) = (0f64, 0f64);
    for z in -(1 << 16)..=(1 << 16) {
        let s = super::super::mlp::logsig(f64::from(z) / Z_SCALE);
        worst16 = worst16.max((f64::from(logsig_q12(z)) - 65535.0 * s).abs());
        worst8 = worst8.max((f64::from(logsig_u8(z)) - 255.0 * s).abs());
    }
    eprintln!("worst LUT error: {worst16:.4} LSB (u16), {worst8:.4} LSB (u8)");
    assert!(worst16 <= 1.0, "{worst16}");
    assert!(worst8 <= 0.505, "{worst8}");
    assert_eq!(logsig_q12(1 << 16), 65535);
    assert_eq!(logsig_q12(-(1 << 16)), 0);
}

#[test]
fn bad_inputs_are_typed_errors() {
    let net = Mlp::new(4, 3, 2, 1);
    let calib = vec![vec![100i16, -200, 300, 0]];
    assert!(quantize_net(&net, &calib).is_ok());
    assert!(matches!(
        quantize_net(&net, &[]),
        Err(ClassifyError::Empty { .. })
    ));
    assert_eq!(
        quantize_net(&net, &[vec![0; 4]]),
        Err(ClassifyError::ZeroVariance)
    );
    assert!(matches!(
        quantize_net(&net, &[vec![1; 5]]),
        Err(ClassifyError::DimensionMismatch { .. })
    ));
    let mut nan = net.clone();
    nan.w2[[1, 2]] = f64::NAN;
    assert!(matches!(
        quantize_net(&nan, &calib),
        Err(ClassifyError::NonFinite { .. })
    ));
    let mut inf = net;
    inf.b1[0] = f64::INFINITY;
    assert!(matches!(
        quantize_net(&inf, &calib),
        Err(ClassifyError::NonFinite { .. })
    ));
    // NaN or infinite features are rejected before the network.
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut v = [1.0, bad, 2.0];
        assert!(matches!(
            super::super::rules::z_normalise(&mut v),
            Err(ClassifyError::NonFinite { .. })
        ));
    }
}

#[test]
fn multipliers_by_hand() {
    assert_eq!(quantize_multiplier(0.5), (1 << 30, 0));
    assert_eq!(quantize_multiplier(0.75), (3 << 29, 0));
    assert_eq!(quantize_multiplier(1.0), (1 << 30, 1));
    assert_eq!(quantize_multiplier(0.1875), (3 << 29, -2));
    assert_eq!(quantize_multiplier(0.0), (0, 0));
    assert_eq!(quantize_multiplier(1e-12), (0, 0));
    for m in [1e-6, 0.0123, 0.37, 0.999_999_999_9, 3.3] {
        let back = multiplier_value(quantize_multiplier(m));
        assert!((back - m).abs() <= m * 2f64.powi(-31), "{m} {back}");
    }
}
