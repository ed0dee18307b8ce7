//! Small helpers: paths, running commands, step headers.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

pub type Result<T> = std::result::Result<T, String>;

/// The workspace root (parent of xtask/).
pub fn root() -> PathBuf {
    let xtask = Path::new(env!("CARGO_MANIFEST_DIR"));
    xtask.parent().unwrap_or(xtask).to_path_buf()
}

/// The cargo that runs us (rustup's when invoked as `cargo xtask`).
pub fn host_cargo() -> Command {
    let mut cmd = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()));
    cmd.current_dir(root());
    cmd
}

fn describe(cmd: &Command) -> String {
    let mut s = cmd.get_program().to_string_lossy().into_owned();
    for a in cmd.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    s
}

/// Runs `cmd` with inherited output; fails with a one-line reason.
pub fn run(cmd: &mut Command) -> Result<()> {
    let what = describe(cmd);
    println!("$ {what}");
    let status = cmd
        .stdin(Stdio::null())
        .status()
        .map_err(|e| format!("cannot start `{what}`: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{what}` failed ({status})"))
    }
}

/// Runs `cmd`, returning its stdout; stderr is passed through.
pub fn output(cmd: &mut Command) -> Result<String> {
    let what = describe(cmd);
    let out = cmd
        .stdin(Stdio::null())
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("cannot start `{what}`: {e}"))?;
    if !out.status.success() {
        return Err(format!("`{what}` failed ({})", out.status));
    }
    String::from_utf8(out.stdout).map_err(|_| format!("`{what}` printed non-UTF-8 output"))
}

/// True if `program` can be started (looked up on PATH).
pub fn have(program: &str) -> bool {
    Command::new(program)
        .arg("--version")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok()
}

/// Runs one named step with a header and its wall time; returns the time in seconds.
pub fn step<T>(name: &str, f: impl FnOnce() -> Result<T>) -> Result<(T, f64)> {
    println!("\n==> {name}");
    let start = Instant::now();
    let value = f().map_err(|e| format!("step '{name}' failed: {e}"))?;
    let secs = start.elapsed().as_secs_f64();
    println!("<== {name}: ok in {secs:.1} s");
    Ok((value, secs))
}

/// Runs `cmd`, echoing its stdout line by line and returning it; fails on non-zero exit.
pub fn run_tee(cmd: &mut Command) -> Result<String> {
    use std::io::BufRead;
    let what = describe(cmd);
    println!("$ {what}");
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start `{what}`: {e}"))?;
    let mut text = String::new();
    if let Some(out) = child.stdout.take() {
        for line in std::io::BufReader::new(out).lines() {
            let line = line.map_err(|e| format!("reading output of `{what}`: {e}"))?;
            println!("{line}");
            text.push_str(&line);
            text.push('\n');
        }
    }
    let status = child
        .wait()
        .map_err(|e| format!("waiting for `{what}`: {e}"))?;
    if status.success() {
        Ok(text)
    } else {
        Err(format!("`{what}` failed ({status})"))
    }
}

/// Sums `test result: ok. N passed; M failed; K ignored` lines of cargo test.
pub fn test_totals(text: &str) -> (u64, u64, u64) {
    let mut totals = (0, 0, 0);
    for line in text.lines().filter_map(|l| l.strip_prefix("test result: ")) {
        for part in line.split(';') {
            let mut words = part.split_whitespace().rev();
            let (Some(kind), Some(n)) = (
                words.next(),
                words.next().and_then(|n| n.parse::<u64>().ok()),
            ) else {
                continue;
            };
            match kind {
                "passed" => totals.0 += n,
                "failed" => totals.1 += n,
                "ignored" => totals.2 += n,
                _ => {}
            }
        }
    }
    totals
}

/// One section of docs/BENCHMARKS.md: a title and its Markdown body.
pub struct Section {
    pub title: &'static str,
    pub body: String,
}
