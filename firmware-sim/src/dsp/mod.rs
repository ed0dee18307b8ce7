//! The Cortex-M4 assembly kernels: the phase step of the stereo stage's
//! refinement, its SGM path steps and the read-out's costs of a whole
//! window ([`PhaseAsm`], in `phase.rs`, with the 16-bit lane kernels in
//! `sgm.rs` and the costs in `costs.rs`) and the `SMLAD` dot-product kernel of
//! the classifier ([`SmladKernel`], in `mlp.rs`, which describes it), which
//! [`PhaseAsm`] also runs for the product's classifier.

#![allow(unsafe_code)]

mod costs;
mod mlp;
mod phase;
mod sgm;

// The bench binary names it; the product runs it through `PhaseAsm`.
#[allow(unused_imports)]
pub use mlp::SmladKernel;
pub use phase::PhaseAsm;
