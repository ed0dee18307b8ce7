//! firmware-sim binary: the same [`firmware_sim::App`] on a Cortex-M under QEMU
//! (`target_os = "none"`, see `mcu.rs`) and on the desktop (see `host.rs`).
//! Both print identical `checksum WxH 0x........` lines.
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(unsafe_code)]

#[cfg(target_os = "none")]
mod dsp;
#[cfg(target_os = "none")]
mod mcu;

#[cfg(not(target_os = "none"))]
mod host;

#[cfg(not(target_os = "none"))]
fn main() -> std::process::ExitCode {
    host::run()
}
