//! `fetch-data`: the aloe stereo pair from Debian's opencv-doc package, and
//! the Middlebury 2014 Motorcycle pair from scikit-image's wheel on PyPI
//! ([`motorcycle`]).

mod motorcycle;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::util::{output, root, run, Result};

const PACKAGE: &str = "opencv-doc";
const SRC_DIR: &str = "usr/share/doc/opencv-doc/examples/data";
const JPEG: &[u8] = &[0xFF, 0xD8, 0xFF];
const PNG: &[u8] = &[0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];
const FILES: [(&str, &[u8]); 3] = [
    ("aloeL.jpg", JPEG),
    ("aloeR.jpg", JPEG),
    ("aloeGT.png", PNG),
];

/// The data root: `$PROTOGIST_DATA`, else `<workspace>/.cache/data` (the
/// same rule as the tests' `data_dir`).
pub fn data_root() -> PathBuf {
    std::env::var_os("PROTOGIST_DATA")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join(".cache/data"))
}

/// `<data root>/aloe`.
pub fn data_dir() -> PathBuf {
    data_root().join("aloe")
}

fn valid(path: &Path, magic: &[u8]) -> bool {
    fs::read(path).is_ok_and(|b| b.len() > magic.len() && b.starts_with(magic))
}

/// Ensures both pairs are in the cache; returns the aloe directory.
pub fn fetch() -> Result<PathBuf> {
    let aloe = fetch_aloe()?;
    motorcycle::fetch(data_root().join("motorcycle"))?;
    Ok(aloe)
}

fn fetch_aloe() -> Result<PathBuf> {
    ensure("aloe", data_dir(), &FILES, fetch_into)
}

/// `(file name, magic)` of a data set.
type Files<'a> = [(&'a str, &'a [u8])];

/// Ensures `files` are in `dir` (each with its magic), else runs
/// `fetch_into(dir, work)` with a scratch `work` directory that is removed
/// afterwards; returns `dir`.
fn ensure(
    what: &str,
    dir: PathBuf,
    files: &Files<'_>,
    fetch_into: impl FnOnce(&Path, &Path) -> Result<()>,
) -> Result<PathBuf> {
    if files
        .iter()
        .all(|(name, magic)| valid(&dir.join(name), magic))
    {
        println!("{what} data already present in {}", dir.display());
        return Ok(dir);
    }
    fs::create_dir_all(&dir).map_err(|e| format!("creating {}: {e}", dir.display()))?;
    let work = dir.join(format!(".fetch-{}", std::process::id()));
    let result = fs::create_dir_all(&work)
        .map_err(|e| format!("creating {}: {e}", work.display()))
        .and_then(|()| fetch_into(&dir, &work));
    let _ = fs::remove_dir_all(&work);
    result?;
    for (name, _) in files {
        println!("  {}", dir.join(name).display());
    }
    Ok(dir)
}

/// Copies each of `files` from `src` to `dir` through a `.part` file,
/// checks its magic, and renames it into place (never a half-written file).
fn install(src: &Path, dir: &Path, files: &Files<'_>, origin: &str) -> Result<()> {
    for (name, magic) in files {
        let from = src.join(name);
        let tmp = dir.join(format!(".{name}.part"));
        fs::copy(&from, &tmp).map_err(|e| format!("copying {}: {e}", from.display()))?;
        if !valid(&tmp, magic) {
            let _ = fs::remove_file(&tmp);
            return Err(format!(
                "{name} from {origin} is empty or not the expected file type"
            ));
        }
        fs::rename(&tmp, dir.join(name)).map_err(|e| format!("renaming {}: {e}", tmp.display()))?;
    }
    Ok(())
}

fn fetch_into(dir: &Path, work: &Path) -> Result<()> {
    let deb = match download_deb(work) {
        Err(e) if crate::setup::is_root() => {
            // Fresh machines may have empty apt lists: refresh once and retry.
            println!("{e}; running apt-get update and retrying");
            run(Command::new("apt-get")
                .arg("update")
                .env("DEBIAN_FRONTEND", "noninteractive"))?;
            download_deb(work)?
        }
        other => other?,
    };
    let tree = work.join("x");
    run(Command::new("dpkg-deb").arg("-x").arg(&deb).arg(&tree))?;
    install(&tree.join(SRC_DIR), dir, &FILES, PACKAGE)
}

fn find_deb(work: &Path) -> Option<PathBuf> {
    fs::read_dir(work)
        .ok()?
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|x| x == "deb"))
}

/// `apt-get download`, else the URL from `--print-uris` with curl.
fn download_deb(work: &Path) -> Result<PathBuf> {
    let first = run(Command::new("apt-get")
        .args(["download", PACKAGE])
        .current_dir(work));
    if let Some(deb) = first.is_ok().then(|| find_deb(work)).flatten() {
        return Ok(deb);
    }
    println!("apt-get download failed; trying the package URL with curl");
    let uris = output(
        Command::new("apt-get")
            .args(["download", "--print-uris", PACKAGE])
            .current_dir(work),
    )?;
    let url = uris
        .split_whitespace()
        .next()
        .map(|u| u.trim_matches('\''))
        .filter(|u| u.starts_with("http"))
        .ok_or_else(|| {
            format!("apt knows no download URL for {PACKAGE} (run `apt-get update` as root first)")
        })?;
    let deb = work.join(format!("{PACKAGE}.deb"));
    run(Command::new("curl")
        .args(["-fsSL", "--retry", "3", "-o"])
        .arg(&deb)
        .arg(url))?;
    Ok(deb)
}
