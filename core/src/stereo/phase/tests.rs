use super::*;
use crate::rng::SplitMix64;

#[test]
fn the_five_tap_x_pass_gives_the_general_bits() {
    let mut rng = SplitMix64::new(0x5eed);
    let phase = Phase::new(&PhaseParams::DEFAULT, 31).unwrap();
    for case in 0..2_000u64 {
        let w = 1 + rng.below(40) as usize;
        let mut v = [0i32; 44];
        for g in v.iter_mut().take(w + 4) {
            // Grey in `U8F8` (0..=255·256), often at its ends.
            *g = match rng.below(4) {
                0 => 0,
                1 => 255 << 8,
                _ => rng.below((255 << 8) + 1) as i32,
            };
        }
        // Random taps within the format (Σ|k| ≤ 2^15) as well as the
        // default's.
        let (mut ch, mut sh) = (phase.c_half, phase.s_half);
        if case % 2 == 1 {
            for k in ch.iter_mut().chain(sh.iter_mut()).take(3) {
                *k = rng.below(1 << 13) as i32 - (1 << 12);
            }
        }
        let (mut want, mut got) = ([[0i16; 2]; 40], [[0i16; 2]; 40]);
        x_pass::<5>(&v[..w + 4], &ch, &sh, &mut want[..w]);
        x_pass5(&v[..w + 4], &ch, &sh, &mut got[..w]);
        assert_eq!(got[..w], want[..w], "case {case}, width {w}");
    }
}
