//! The Cortex-M4 assembly kernels: the phase step of the stereo stage's
//! refinement and its SGM path steps ([`PhaseAsm`], in `phase.rs`, with the
//! 16-bit lane kernels in `sgm.rs`) and the `SMLAD` dot-product kernel of
//! the classifier ([`SmladKernel`], in `mlp.rs`, which describes it), which
//! [`PhaseAsm`] also runs for the product's classifier.

#![allow(unsafe_code)]

mod mlp;
mod phase;
mod sgm;

// The bench binary names it; the product runs it through `PhaseAsm`.
#[allow(unused_imports)]
pub use mlp::SmladKernel;
pub use phase::PhaseAsm;
