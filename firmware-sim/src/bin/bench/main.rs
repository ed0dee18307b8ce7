//! `bench`: the bench firmware, the stage harnesses of
//! [`firmware_sim::bench`] one by one (conspicuity frame after frame,
//! figure-ground on the ground-truth disparity, the stereo engine at its
//! named points, the classifier with the benchmark networks), on a
//! Cortex-M under QEMU (`target_os = "none"`, see `mcu.rs`) and on the
//! desktop (see `host.rs`). Both print identical `checksum` and `edges`
//! lines; `cargo xtask bench` reads its instruction counts.
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(unsafe_code)]

#[cfg(target_os = "none")]
#[path = "../../board.rs"]
mod board;
#[cfg(target_os = "none")]
#[path = "../../dsp/mod.rs"]
mod dsp;
#[cfg(target_os = "none")]
mod mcu;

#[cfg(not(target_os = "none"))]
mod host;

#[cfg(not(target_os = "none"))]
fn main() -> std::process::ExitCode {
    host::run()
}
