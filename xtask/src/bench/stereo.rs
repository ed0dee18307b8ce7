//! The stereo sections: the engine on the Cortex-M4, the named operating
//! points, and Aloe and Motorcycle on the host beside OpenCV.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::{protogist_json, NOT_YET};
use crate::data::data_root;
use crate::util::{output, root, run as run_cmd, Result, Section};

/// The core stereo stage on the board (issue 3 §4): instructions per pixel
/// per step, and its scratch, from the firmware's `stereo` lines.
pub(super) fn stereo_m4(stdout: &str) -> Section {
    let mut body = String::from(
        "The stereo engine `protogist::stereo::c2f` in the firmware \
         (`firmware-sim/src/bench/stereo_run.rs`) at the point `full`: the demo scene's 160x120 pair, \
         32 disparities (`C2fParams::FULL`: `max_disp` 31, one pyramid level per c2f level, 2 \
         coarse levels, windows of 5 candidates, band 2, 5-path SGM, no pooling; tables \
         `firmware-sim/data/dem_c2f_l{0,1,2}.bin`), RGB rows rendered by the simulated camera as \
         the engine asks for them and the map folded into the checksum row by row. Same QEMU \
         setup as above. The `levels` step includes the camera's rendering (every level reads \
         each frame pixel once, so 3 renders per eye), which `camera-within-levels` measures \
         alone; the target is judged on the engine, the total minus the camera: the frames are \
         the engine's input, which a camera's DMA would leave in memory (two RGB frames do not \
         fit in the board's RAM or flash beside the rest of the firmware).\n\n\
         | step | instructions / pixel |\n|---|---|\n",
    );
    let mut total = None;
    for l in stdout.lines() {
        if let ["ipp", step, "160x120", v] = l.split_whitespace().collect::<Vec<_>>()[..] {
            if step == "stereo-engine" {
                total = v.parse::<f64>().ok();
                body.push_str(&format!("| **engine: total − camera** | **{v}** |\n"));
            } else if let Some(name) = step.strip_prefix("stereo-") {
                body.push_str(&format!("| {name} | {v} |\n"));
            } else if step == "stereo" {
                body.push_str(&format!("| total, with the camera | {v} |\n"));
            }
        }
    }
    let scratch = stdout.lines().find_map(|l| {
        l.strip_prefix("scratch stereo 160x120 ")
            .and_then(|b| b.trim().parse::<u64>().ok())
    });
    let (Some(total), Some(scratch)) = (total, scratch) else {
        return Section {
            title: "Stereo on the Cortex-M4 (QEMU)",
            body: NOT_YET.into(),
        };
    };
    if let Some(c) = stdout.lines().find(|l| l.starts_with("checksum stereo ")) {
        body.push_str(&format!(
            "\nResult line (equal on the desktop run): `{c}`\n"
        ));
    }
    // The operating points within the instruction target (next section).
    let within: Vec<String> = points(stdout)
        .iter()
        .filter_map(|p| {
            let e = p.get("engine").parse::<f64>().ok()?;
            (e <= 1500.0).then(|| format!("{} ({e:.0}, finest level {})", p.name, p.finest))
        })
        .collect();
    let within = if within.is_empty() {
        "none".to_string()
    } else {
        within.join(", ")
    };
    // `scratch stereo@NAME WxH BYTES`: the points with the phase refinement.
    let phase_scratch: Vec<String> = stdout
        .lines()
        .filter_map(|l| l.strip_prefix("scratch stereo@"))
        .filter_map(|l| match l.split_whitespace().collect::<Vec<_>>()[..] {
            [name, _, bytes] => Some(format!("{name} {bytes}")),
            _ => None,
        })
        .collect();
    let phase_scratch = if phase_scratch.is_empty() {
        String::new()
    } else {
        format!(
            " With the phase refinement's buffers (`c2f::scratch_bytes` of the point): **{} \
             bytes**.",
            phase_scratch.join(", ")
        )
    };
    body.push_str(&format!(
        "\n**Targets** (issue 3 §4): 1,500 instructions/px or fewer: by `full` **{}, \
         {total:.0}** ({:.1}x the target); named points within it (next section): \
         **{within}**; scratch ≤ 96 KB (98,304 bytes) beyond the two frames: **{scratch} bytes \
         ({:.1} KB), {}** (`c2f::scratch_bytes(160, 120, &C2fParams::FULL)`).{phase_scratch} \
         The full-search engine, removed, took 101,581 instructions/px (docs/STEREO.md, What \
         was tried).\n",
        if total <= 1500.0 {
            "reached"
        } else {
            "not reached"
        },
        total / 1500.0,
        scratch as f64 / 1024.0,
        if scratch <= 98_304 {
            "reached"
        } else {
            "not reached"
        },
    ));
    Section {
        title: "Stereo on the Cortex-M4 (QEMU)",
        body,
    }
}

/// One `point stereo` line of the firmware: name, window half width,
/// band, and the `key=value` figures.
struct Point<'a> {
    name: &'a str,
    radius: &'a str,
    band: &'a str,
    /// The left-right check's right map: `off`, `read` or `derived`.
    lr: &'a str,
    /// SGM paths.
    paths: &'a str,
    /// The finest level run (0: the full size).
    finest: &'a str,
    /// The phase refinement (`1`: on).
    phase: &'a str,
    values: Vec<(&'a str, &'a str)>,
}

impl Point<'_> {
    fn get(&self, key: &str) -> &str {
        self.values
            .iter()
            .find(|(k, _)| *k == key)
            .map_or("?", |(_, v)| v)
    }
}

fn points(stdout: &str) -> Vec<Point<'_>> {
    stdout
        .lines()
        .filter_map(|l| {
            let mut it = l.split_whitespace();
            if (it.next(), it.next()) != (Some("point"), Some("stereo")) {
                return None;
            }
            let name = it.next()?;
            let _frame = it.next()?;
            let values: Vec<(&str, &str)> = it.filter_map(|kv| kv.split_once('=')).collect();
            let find = |k: &str| values.iter().find(|(key, _)| *key == k).map(|(_, v)| *v);
            Some(Point {
                name,
                radius: find("radius")?,
                band: find("band")?,
                lr: find("lr").unwrap_or("read"),
                paths: find("paths").unwrap_or("5"),
                finest: find("finest").unwrap_or("0"),
                phase: find("phase").unwrap_or("0"),
                values,
            })
        })
        .collect()
}

/// The named operating points (issue 19 §5): the firmware's `point stereo`
/// lines (M4 instructions per pixel) beside `protogist stereo --point NAME`
/// on Aloe and Motorcycle, 160 px, D = 32.
pub(super) fn stereo_points(stdout: &str) -> Section {
    let title = "Stereo operating points: instructions against accuracy";
    let pts = points(stdout);
    if pts.is_empty() {
        return Section {
            title,
            body: NOT_YET.into(),
        };
    }
    let mut body = String::from(
        "The named points of the engine (`C2fParams::NAMED`, docs/STEREO.md, section \
         Operating points), the same tables: R the window half width (2R + 1 candidates at the \
         finer levels), band the cell groups within b px of the window's centre, LR the \
         left-right check's right map (`read`: the right eye read out; `derived`: from the left \
         map's path sums as in OpenCV SGBM, no right eye; `off`: no check), paths the SGM paths \
         (3: without the two diagonals), finest the finest level run (1: the half-size map, each \
         cell over its 2x2 block), phase the refinement to the frame's resolution by phase (its \
         cost inside costs + picks). Instructions per pixel on the M4 from the firmware's \
         `point stereo` lines (same QEMU run as above; the camera excluded as in the previous \
         section). Accuracy from `cargo run --release -- stereo --point NAME --width 160 \
         --max-disp 32 --json` on Aloe and on the held-out Motorcycle: bad-2 % over estimated \
         pixels / over all GT pixels; OpenCV on the same pairs in the next two sections.\n\n\
         | point | R | band | LR | paths | finest | phase | cells / px | votes | SGM | \
         costs + picks | filters | **engine** | Aloe est / all | Motorcycle est / all |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let pairs = [aloe_files(), motorcycle_files()];
    for p in &pts {
        let cells = p
            .get("cells")
            .parse::<f64>()
            .map_or_else(|_| "?".into(), |c| format!("{:.1}", c / 19_200.0));
        let mut row = format!(
            "| {} | {} | {} | {} | {} | {} | {} | {cells} | {} | {} | {} | {} | **{}** |",
            p.name,
            p.radius,
            p.band,
            p.lr,
            p.paths,
            p.finest,
            p.phase,
            p.get("cells-votes"),
            p.get("sgm"),
            p.get("costs-picks"),
            p.get("filters"),
            p.get("engine"),
        );
        for [l, r, gt] in &pairs {
            row.push_str(&format!(" {} |", point_accuracy([l, r, gt], p.name)));
        }
        body.push_str(&row);
        body.push('\n');
    }
    body.push_str(
        "\nThe steps that do not depend on the cells (filters, and the camera-free levels) \
         stay; SGM and the costs scale with the window, the votes with the cells; the derived \
         check drops the right eye's votes, costs and SGM, and 3 paths two fifths of the SGM; \
         stopping at level 1 drops level 0, about three quarters of every step.\n",
    );
    Section { title, body }
}

/// Aloe's left, right and GT paths under the data root.
fn aloe_files() -> [PathBuf; 3] {
    let dir = data_root().join("aloe");
    [
        dir.join("aloeL.jpg"),
        dir.join("aloeR.jpg"),
        dir.join("aloeGT.png"),
    ]
}

/// Motorcycle's left, right and GT paths under the data root.
fn motorcycle_files() -> [PathBuf; 3] {
    let dir = data_root().join("motorcycle");
    [
        dir.join("motorcycle_left.png"),
        dir.join("motorcycle_right.png"),
        dir.join("motorcycle_disp.npz"),
    ]
}

/// The arguments of `protogist stereo` at the named `point` on `files`
/// (left, right, GT) at width `w` and max disparity `d`, JSON into `out`.
fn point_args(files: [&Path; 3], point: &str, w: &str, d: &str, out: &Path) -> Vec<String> {
    let [l, r, gt] = files.map(|f| f.to_string_lossy().into_owned());
    [
        "stereo",
        "--left",
        &l,
        "--right",
        &r,
        "--gt",
        &gt,
        "--point",
        point,
        "--width",
        w,
        "--max-disp",
        d,
        "--json",
        "--out",
        &out.to_string_lossy(),
    ]
    .map(str::to_string)
    .to_vec()
}

/// `est / all` bad-2 % of the named `point` on `files` (160 px, D 32), or
/// "not yet measured".
fn point_accuracy(files: [&Path; 3], point: &str) -> String {
    if !files[2].is_file() {
        return format!("{NOT_YET} (`cargo xtask fetch-data`)");
    }
    let args = point_args(
        files,
        point,
        "160",
        "32",
        &root().join("target/bench-points"),
    );
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    protogist_json(&args)
        .and_then(|v| {
            let f = v.get("final")?;
            let g = |k: &str| f.get(k).and_then(serde_json::Value::as_f64);
            Some(format!(
                "{:.1} / {:.1}",
                g("bad2_estimated")?,
                g("bad2_all")?
            ))
        })
        .unwrap_or_else(|| NOT_YET.into())
}

pub(super) fn stereo_aloe(stdout: &str) -> Section {
    let files = aloe_files();
    let body = format!(
        "`cargo run --release -- stereo --left aloeL.jpg --right aloeR.jpg --gt aloeGT.png \
         --point NAME --width W --max-disp D --json --out DIR`: core's engine at each named \
         point, ms its run alone, the best of at least 15 runs over at least 1 s, single \
         thread. bad-k: % of pixels off by more than k px, over pixels with an estimate, and \
         over all GT pixels with a missing estimate counted as an error.\n\n{}",
        point_rows(stdout, &files)
    );
    stereo_pair("Stereo on Middlebury Aloe", body, &files, "aloe")
}

pub(super) fn stereo_motorcycle(stdout: &str) -> Section {
    let files = motorcycle_files();
    let body = format!(
        "scikit-image 0.26.0's copy of Motorcycle (741x500, GT float32 px in an npz), fetched \
         by `cargo xtask fetch-data`; the pair P2 was chosen on. `cargo run --release -- stereo \
         --left motorcycle_left.png --right motorcycle_right.png --gt motorcycle_disp.npz \
         --point NAME --width W --max-disp D --json --out DIR`; metrics as in the Aloe \
         section.\n\n{}",
        point_rows(stdout, &files)
    );
    stereo_pair(
        "Stereo on Middlebury 2014 Motorcycle",
        body,
        &files,
        "motorcycle",
    )
}

/// The section of one pair: `body` (the point rows) and OpenCV's rows, or
/// "not yet measured" without the data.
fn stereo_pair(title: &'static str, body: String, files: &[PathBuf; 3], pair: &str) -> Section {
    if !files[2].is_file() {
        return Section {
            title,
            body: format!("{NOT_YET}: run `cargo xtask fetch-data`.\n"),
        };
    }
    let dir = files[2].parent().unwrap_or(Path::new("."));
    Section {
        title,
        body: format!("{body}{}", opencv_rows(dir, pair)),
    }
}

/// The table of the named points (their names from the firmware's `point
/// stereo` lines) on `files` at 160 px D 32 and 320 px D 64.
fn point_rows(stdout: &str, files: &[PathBuf; 3]) -> String {
    let [l, r, gt] = files;
    let mut out = String::from(STEREO_TABLE_HEAD);
    for (w, d) in [("160", "32"), ("320", "64")] {
        for p in points(stdout) {
            out.push_str(&stereo_row([l, r, gt], p.name, w, d));
        }
    }
    out
}

/// One table row: `protogist stereo` at the named `point` on `files`
/// (left, right, GT) at width `w` and max disparity `d`, or "not yet
/// measured".
fn stereo_row(files: [&Path; 3], point: &str, w: &str, d: &str) -> String {
    let out_dir = root().join("target/bench-stereo");
    let mut args = point_args(files, point, w, d, &out_dir);
    args.extend(["--time-at-least".to_string(), TIMED_MS.to_string()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    protogist_json(&args)
        .and_then(|v| {
            let f = v.get("final")?;
            let g = |k: &str| f.get(k).and_then(serde_json::Value::as_f64);
            Some(format!(
                "| {point} | {w} | {d} | {:.1} / {:.1} / {:.1} | {:.1} / {:.1} / {:.1} | {:.2} | {:.1} % | {} |\n",
                g("bad1_estimated")?, g("bad2_estimated")?, g("bad4_estimated")?,
                g("bad1_all")?, g("bad2_all")?, g("bad4_all")?,
                g("mae")?, g("density")?, ms(v.get("stereo_ms")?.as_f64()?)
            ))
        })
        .unwrap_or_else(|| format!("| {point} | {w} | {d} | {NOT_YET} | | | | |\n"))
}

/// Milliseconds as printed: one decimal below 100 ms (the fast engines sit
/// beside SGBM's few ms), whole ms above.
fn ms(v: f64) -> String {
    if v < 100.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.0}")
    }
}

/// The header of the point tables.
const STEREO_TABLE_HEAD: &str = "| point | width | D | bad-1 / 2 / 4 (estimated) | bad-1 / 2 / 4 (all GT) | MAE px | density | ms |\n\
     |---|---|---|---|---|---|---|---|\n";

/// Each host stereo time (ours with `--engine core`, and OpenCV's) is the
/// best of at least 15 runs made over at least this many ms: with 15 runs
/// alone, a burst of load on the shared machine could cover all of them
/// (one bench gave 3.2 ms for a 2.0 ms run, and the next 17.4 for 10.7).
const TIMED_MS: u32 = 1000;

/// OpenCV StereoSGBM / StereoBM on the same data and protocol, from
/// `scripts/opencv_baseline.py --pair PAIR` in a venv with pinned versions.
fn opencv_rows(data: &Path, pair: &str) -> String {
    let mut out = String::from(
        "\nOpenCV under the same protocol (area-averaged images, GT as the mean of its known \
         pixels), single thread, ms the best of at least 15 runs over at least 1 s, from `scripts/opencv_baseline.py` with the versions pinned in \
         `scripts/requirements-opencv.txt` (a venv in `target/venv-opencv`). SGBM is colour, \
         P1 = 8·3·bs², P2 = 32·3·bs²; BM is grey. Both search numDisparities = D (0..D−1, \
         as in the issue's measurement; ours searches 0..D).\n\n\
         | matcher | block | width | D | bad-2 (estimated) | bad-2 (all GT) | density | ms |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    let venv = root().join("target/venv-opencv");
    let py = venv.join("bin/python");
    let setup = || -> Result<()> {
        if !py.exists() {
            run_cmd(Command::new("python3").arg("-m").arg("venv").arg(&venv))?;
        }
        run_cmd(
            Command::new(&py)
                .args(["-m", "pip", "install", "-q", "-r"])
                .arg(root().join("scripts/requirements-opencv.txt")),
        )
    };
    let rows = setup().and_then(|()| {
        output(
            Command::new(&py)
                .arg(root().join("scripts/opencv_baseline.py"))
                .arg("--data")
                .arg(data)
                .args(["--pair", pair, "--config", "160:32", "--config", "320:64"])
                .args(["--min-seconds", &format!("{}", f64::from(TIMED_MS) / 1e3)]),
        )
    });
    let rows = match rows {
        Ok(r) => r,
        Err(e) => return format!("\nOpenCV: {NOT_YET}: {e}\n"),
    };
    for line in rows.lines() {
        let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        let f = |k: &str| {
            v.get(k)
                .and_then(serde_json::Value::as_f64)
                .unwrap_or(f64::NAN)
        };
        let m = v
            .get("matcher")
            .and_then(serde_json::Value::as_str)
            .unwrap_or("?");
        out.push_str(&format!(
            "| {m} | {} | {} | {} | {:.1} | {:.1} | {:.1} % | {:.1} |\n",
            f("block"),
            f("width"),
            f("max_disp"),
            f("bad2_estimated"),
            f("bad2_all"),
            f("density"),
            f("ms")
        ));
    }
    if pair != "aloe" {
        return out;
    }
    out.push_str(
        "\nIssue 3 quotes, for OpenCV 5.0, SGBM bad-2 over all GT pixels 33.6 % at 160 px and \
         33.5 % at 320 px (BM 53.0 % and 46.3 %). With numDisparities = D the table above is \
         within 0.6 point of its SGBM figures; an earlier version of the script searched D + 1 \
         rounded up to a multiple of 16 and got 42.4 % and 37.7 %.\n",
    );
    out
}

#[cfg(test)]
mod stereo_tests {
    use super::{point_args, points, stereo_m4};
    use std::path::Path;

    #[test]
    fn a_point_row_runs_the_named_point_on_the_pair() {
        let (l, r, gt) = (Path::new("l.png"), Path::new("r.png"), Path::new("gt.png"));
        let a = point_args([l, r, gt], "fast", "160", "32", Path::new("out"));
        let at = |flag: &str| {
            let i = a.iter().position(|x| x == flag).unwrap();
            a[i + 1].as_str()
        };
        assert_eq!(a[0], "stereo");
        assert_eq!(
            (at("--point"), at("--width"), at("--max-disp")),
            ("fast", "160", "32")
        );
        assert_eq!(
            (at("--left"), at("--right"), at("--gt")),
            ("l.png", "r.png", "gt.png")
        );
        assert!(a.iter().any(|x| x == "--json"));
    }

    #[test]
    fn point_lines_are_read_field_by_field() {
        let out = "ipp stereo 160x120 1.0\n\
                   point stereo r1b1 160x120 radius=1 band=1 lr=derived paths=3 engine=7355.0 cells=201756 \
                   levels=3388.6 cells-votes=2478.2\n\
                   point stereo all 160x120 radius=2 band=- engine=9.5 cells=3\n\
                   point stereo broken 160x120 engine=1\n\
                   point stereo r2b1l3h 160x120 radius=2 band=1 lr=derived paths=3 finest=1 engine=1325.3\n";
        let p = points(out);
        assert_eq!(p.len(), 3, "the line without radius and band is skipped");
        assert_eq!((p[0].finest, p[2].finest), ("0", "1"), "0 when not named");
        assert_eq!((p[0].name, p[0].radius, p[0].band), ("r1b1", "1", "1"));
        assert_eq!(
            (p[0].lr, p[1].lr),
            ("derived", "read"),
            "read when not named"
        );
        assert_eq!((p[0].paths, p[1].paths), ("3", "5"), "5 when not named");
        assert_eq!(p[0].get("engine"), "7355.0");
        assert_eq!(p[0].get("cells-votes"), "2478.2");
        assert_eq!(p[0].get("sgm"), "?");
        assert_eq!((p[1].name, p[1].band, p[1].get("cells")), ("all", "-", "3"));
    }

    #[test]
    fn stereo_section_reads_the_firmware_lines() {
        let out = "ipp capture 160x120 528.0\nchecksum stereo 160x120 0x4554b818 on=15823\n\
                   ipp stereo-pyramid 160x120 2372.4\nipp stereo-readout 160x120 62886.3\n\
                   ipp stereo 160x120 108554.7\nipp stereo-engine 160x120 1400.2\n\
                   scratch stereo 160x120 76616\n";
        let s = stereo_m4(out);
        assert!(s.body.contains("| pyramid | 2372.4 |"), "{}", s.body);
        assert!(s.body.contains("| readout | 62886.3 |"));
        assert!(s.body.contains("| total, with the camera | 108554.7 |"));
        assert!(s.body.contains("**1400.2**"));
        assert!(s.body.contains("by `full` **reached, 1400**"), "{}", s.body);
        assert!(
            s.body.contains("within it (next section): **none**"),
            "{}",
            s.body
        );
        let with_points = format!(
            "{out}point stereo a 160x120 radius=2 band=1 paths=3 finest=1 engine=1325.3\n\
             point stereo b 160x120 radius=2 band=1 engine=1600.0\n"
        );
        assert!(
            stereo_m4(&with_points)
                .body
                .contains("**a (1325, finest level 1)**"),
            "{}",
            stereo_m4(&with_points).body
        );
        assert!(s.body.contains("76616 bytes"));
        assert!(s.body.contains("0x4554b818"));
        assert!(!s.body.contains("| capture |"));
        assert_eq!(stereo_m4("ipp capture 160x120 1.0\n").body, super::NOT_YET);
        let over = out.replace(
            "stereo-engine 160x120 1400.2",
            "stereo-engine 160x120 1500.6",
        );
        assert!(stereo_m4(&over).body.contains("**not reached, 1501**"));
    }
}
