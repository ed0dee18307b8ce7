//! System prerequisites: Debian packages and rustup components.

use std::process::{Command, Stdio};

use crate::util::{have, output, run, Result};

pub const THUMB: &str = "thumbv7em-none-eabihf";
/// Needed always: cross linker/binutils and the emulator.
const BASE_PACKAGES: [&str; 2] = ["gcc-arm-none-eabi", "qemu-system-arm"];
/// Needed when rustup has no thumb target: Debian's toolchain plus its std source (build-std).
const BUILD_STD_PACKAGES: [&str; 3] = ["rustc-web", "cargo-web", "rust-web-src"];

/// True if rustup has the prebuilt thumbv7em std (then no build-std is needed).
pub fn rustup_has_thumb() -> bool {
    let mut cmd = Command::new("rustup");
    cmd.args(["target", "list", "--installed"])
        .stderr(Stdio::null());
    output(&mut cmd).is_ok_and(|s| s.lines().any(|l| l.trim() == THUMB))
}

fn dpkg_installed(pkg: &str) -> bool {
    let mut cmd = Command::new("dpkg-query");
    cmd.args(["-W", "-f=${Status}", pkg]).stderr(Stdio::null());
    output(&mut cmd).is_ok_and(|s| s.trim() == "install ok installed")
}

pub fn is_root() -> bool {
    output(Command::new("id").arg("-u")).is_ok_and(|s| s.trim() == "0")
}

/// Installs missing Debian packages when root; otherwise names them and fails.
pub fn ensure_packages() -> Result<()> {
    let mut wanted: Vec<&str> = BASE_PACKAGES.to_vec();
    if !rustup_has_thumb() {
        wanted.extend(BUILD_STD_PACKAGES);
    }
    let missing: Vec<&str> = wanted.into_iter().filter(|p| !dpkg_installed(p)).collect();
    if missing.is_empty() {
        println!("system packages present");
        return Ok(());
    }
    let list = missing.join(" ");
    if !is_root() {
        return Err(format!(
            "missing Debian packages: {list}; install them as root with: apt-get update && apt-get install -y {list}"
        ));
    }
    println!("installing missing Debian packages: {list}");
    run(Command::new("apt-get")
        .arg("update")
        .env("DEBIAN_FRONTEND", "noninteractive"))?;
    run(Command::new("apt-get")
        .args(["install", "-y", "--no-install-recommends"])
        .args(&missing)
        .env("DEBIAN_FRONTEND", "noninteractive"))
}

/// Makes sure `cargo fmt` and `cargo clippy` work.
pub fn ensure_components() -> Result<()> {
    if have("rustup") {
        let installed = output(Command::new("rustup").args(["component", "list", "--installed"]))?;
        let missing: Vec<&str> = ["rustfmt", "clippy"]
            .into_iter()
            .filter(|c| !installed.lines().any(|l| l.starts_with(&format!("{c}-"))))
            .collect();
        if !missing.is_empty() {
            // rustup downloads components; on a registry-only network this fails.
            run(Command::new("rustup")
                .args(["component", "add"])
                .args(&missing))
            .map_err(|e| {
                format!("{e}; rustup could not add {missing:?} (it needs its download server)")
            })?;
        }
    }
    for sub in ["fmt", "clippy"] {
        let mut cmd = crate::util::host_cargo();
        cmd.args([sub, "--version"])
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        if !cmd.status().is_ok_and(|s| s.success()) {
            return Err(format!(
                "`cargo {sub}` is not available; install the rustup component"
            ));
        }
    }
    println!("rustfmt and clippy present");
    Ok(())
}

pub fn ensure_all() -> Result<()> {
    ensure_packages()?;
    ensure_components()
}
