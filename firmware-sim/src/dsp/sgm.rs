//! The lane kernels of the SGM path steps of [`PhaseAsm`](super::PhaseAsm):
//! 16-bit lane operations (`USUB16`, `SEL`, `UQADD16`, `UADD16`) on pairs of
//! candidates.

/// The lane-wise minimum of two pairs of `u16` (`USUB16` sets GE where
/// `a >= b`, `SEL` then takes `b`).
#[inline(always)]
pub(super) fn min16(a: u32, b: u32) -> u32 {
    let r: u32;
    // SAFETY: registers only.
    unsafe {
        core::arch::asm!(
            "usub16 {t}, {a}, {b}",
            "sel {r}, {b}, {a}",
            a = in(reg) a,
            b = in(reg) b,
            t = out(reg) _,
            r = lateout(reg) r,
            options(pure, nomem, nostack),
        );
    }
    r
}

/// Lane-wise `a + b`, saturating at 65535.
#[inline(always)]
pub(super) fn uqadd16(a: u32, b: u32) -> u32 {
    let r: u32;
    // SAFETY: registers only.
    unsafe {
        core::arch::asm!("uqadd16 {r}, {a}, {b}", a = in(reg) a, b = in(reg) b, r = lateout(reg) r,
            options(pure, nomem, nostack, preserves_flags));
    }
    r
}

/// Lane-wise `a + b` modulo 2^16.
#[inline(always)]
pub(super) fn uadd16(a: u32, b: u32) -> u32 {
    let r: u32;
    // SAFETY: registers only (GE flags only).
    unsafe {
        core::arch::asm!("uadd16 {r}, {a}, {b}", a = in(reg) a, b = in(reg) b, r = lateout(reg) r,
            options(pure, nomem, nostack));
    }
    r
}

/// Lane-wise `a − b` modulo 2^16.
#[inline(always)]
pub(super) fn usub16(a: u32, b: u32) -> u32 {
    let r: u32;
    // SAFETY: registers only (GE flags only).
    unsafe {
        core::arch::asm!("usub16 {r}, {a}, {b}", a = in(reg) a, b = in(reg) b, r = lateout(reg) r,
            options(pure, nomem, nostack));
    }
    r
}

/// `L` of one SGM path step for 5 candidates, two per word: `d = 0, 1` in
/// the first (candidate `2i` in the low half), `2, 3` in the second, 4 in
/// the low half of the third. With `h` the predecessor's state `p` and
/// `pad` for the candidates outside it (`h(−1) = h(5) = pad16`),
/// `L(d) = c(d) + min(P2, h(d), min(h(d − 1), h(d + 1)) + P1)`: the
/// neighbours are the words shifted by a half (`lsl`/`lsr`/`orr`), the
/// minima `USUB16` + `SEL` (GE set where the first is not below the
/// second), `+ P1` saturating (`UQADD16`), `+ c` plain (`UADD16`).
///
/// The same integers as the portable step under the kernel contract
/// ([`PhaseKernel::sgm_step5`](firmware_sim::pg::stereo::phase::PhaseKernel::sgm_step5)): every lane value is at most 65535; a
/// sum `min(..) + P1` above 65535 saturates to 65535, which is not below
/// `P2` (at most 65535), so the minimum with `P2` is `P2` either way;
/// `pad16 = min(pad, 65535)` (the portable pad is 0 or `2^30`) acts as
/// the portable pad for the same reason; `c(d) + min(..) <= c(d) + P2 <=
/// 65535` does not wrap. The third word's high lane is don't-care.
#[inline(always)]
pub(super) fn sgm_lanes(
    c: &[u16; 5],
    p: &[u16; 5],
    pad16: u32,
    p1x2: u32,
    p2x2: u32,
) -> (u32, u32, u32) {
    let (b0, b1, b2): (u32, u32, u32);
    // SAFETY: reads the 10 bytes of `p` and of `c` (two words, possibly
    // unaligned, which the Cortex-M4 allows for `ldr`, and a halfword
    // each); registers only otherwise; no stack, flags clobbered.
    unsafe {
        core::arch::asm!(
            "ldr {h1}, [{pp}, #4]",
            "ldrh {h2}, [{pp}, #8]",
            "ldr {h0}, [{pp}]",
            // B0 = (pad, h0), B1 = (h1, h2), min(B0, B1): d = 0, 1.
            "lsl {b0}, {h0}, #16",
            "orr {b0}, {b0}, {pad}",
            "lsr {b1}, {h0}, #16",
            "orr {b1}, {b1}, {h1}, lsl #16",
            "usub16 {pp}, {b0}, {b1}",
            "sel {b0}, {b1}, {b0}",
            // B2 = (h3, ·), min(B2, pad): d = 4.
            "lsr {b2}, {h1}, #16",
            "usub16 {pp}, {b2}, {pad}",
            "sel {b2}, {pad}, {b2}",
            // A1 = (h3, h4), min(B1, A1): d = 2, 3.
            "lsr {pad}, {h1}, #16",
            "orr {pad}, {pad}, {h2}, lsl #16",
            "usub16 {pp}, {b1}, {pad}",
            "sel {b1}, {pad}, {b1}",
            // + P1, saturating.
            "uqadd16 {b0}, {b0}, {p1}",
            "uqadd16 {b1}, {b1}, {p1}",
            "uqadd16 {b2}, {b2}, {p1}",
            // min with h.
            "usub16 {pp}, {b0}, {h0}",
            "sel {b0}, {h0}, {b0}",
            "usub16 {pp}, {b1}, {h1}",
            "sel {b1}, {h1}, {b1}",
            "usub16 {pp}, {b2}, {h2}",
            "sel {b2}, {h2}, {b2}",
            // min with P2.
            "usub16 {pp}, {b0}, {p2}",
            "sel {b0}, {p2}, {b0}",
            "usub16 {pp}, {b1}, {p2}",
            "sel {b1}, {p2}, {b1}",
            "usub16 {pp}, {b2}, {p2}",
            "sel {b2}, {p2}, {b2}",
            // + c.
            "ldr {h0}, [{cp}]",
            "ldr {h1}, [{cp}, #4]",
            "ldrh {h2}, [{cp}, #8]",
            "uadd16 {b0}, {b0}, {h0}",
            "uadd16 {b1}, {b1}, {h1}",
            "uadd16 {b2}, {b2}, {h2}",
            pp = inout(reg) p.as_ptr() => _,
            cp = in(reg) c.as_ptr(),
            pad = inout(reg) pad16 => _,
            p1 = in(reg) p1x2,
            p2 = in(reg) p2x2,
            h0 = out(reg) _,
            h1 = out(reg) _,
            h2 = out(reg) _,
            b0 = out(reg) b0,
            b1 = out(reg) b1,
            b2 = out(reg) b2,
            options(nostack, readonly, pure),
        );
    }
    (b0, b1, b2)
}

/// Adds the five `L` of [`sgm_lanes`] to `acc` (`UXTAH`) and returns the
/// state `L − min L` (the minimum of the five lanes in both halves, then
/// `USUB16`, which cannot borrow).
#[inline(always)]
pub(super) fn sgm_settle(l01: u32, l23: u32, l4: u32, acc: &mut [u32; 5]) -> [u16; 5] {
    let (s01, s23, s4): (u32, u32, u32);
    // SAFETY: reads and writes the five words of `acc` (word-aligned, a
    // `[u32; 5]`); registers only otherwise; no stack, flags clobbered.
    unsafe {
        core::arch::asm!(
            "ldr {t}, [{ap}]",
            "uxtah {t}, {t}, {l01}",
            "str {t}, [{ap}]",
            "ldr {t}, [{ap}, #4]",
            "uxtah {t}, {t}, {l01}, ror #16",
            "str {t}, [{ap}, #4]",
            "ldr {t}, [{ap}, #8]",
            "uxtah {t}, {t}, {l23}",
            "str {t}, [{ap}, #8]",
            "ldr {t}, [{ap}, #12]",
            "uxtah {t}, {t}, {l23}, ror #16",
            "str {t}, [{ap}, #12]",
            "ldr {t}, [{ap}, #16]",
            "uxtah {t}, {t}, {l4}",
            "str {t}, [{ap}, #16]",
            // m = min of the five, in both halves.
            "usub16 {t}, {l01}, {l23}",
            "sel {m}, {l23}, {l01}",
            "mvn {u}, #0",
            "bfi {u}, {l4}, #0, #16",
            "usub16 {t}, {m}, {u}",
            "sel {m}, {u}, {m}",
            "ror {u}, {m}, #16",
            "usub16 {t}, {m}, {u}",
            "sel {m}, {u}, {m}",
            "usub16 {l01}, {l01}, {m}",
            "usub16 {l23}, {l23}, {m}",
            "usub16 {l4}, {l4}, {m}",
            ap = in(reg) acc.as_mut_ptr(),
            l01 = inout(reg) l01 => s01,
            l23 = inout(reg) l23 => s23,
            l4 = inout(reg) l4 => s4,
            t = out(reg) _,
            u = out(reg) _,
            m = out(reg) _,
            options(nostack),
        );
    }
    [
        s01 as u16,
        (s01 >> 16) as u16,
        s23 as u16,
        (s23 >> 16) as u16,
        s4 as u16,
    ]
}
