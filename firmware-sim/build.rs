//! Link setup for bare-metal (thumb*) builds; for every build, the two
//! seeded benchmark networks of `src/bench/mlp_run.rs` (see `bench_blob`)
//! and the frames' RGB565 CIELUV and grey tables (see `luv565_table`,
//! `grey565_tables`).

use std::{env, fs, path::PathBuf};

// The frames' RGB565 expansion, the same source as the crate's.
#[allow(dead_code)]
#[path = "src/rgb565.rs"]
mod rgb565;

/// The CIELUV table of `src/stereo_camera.rs` (`LUV565`): for every
/// RGB565 value `v`, core's `LUV_TABLES.convert(expand_rgb565(v))` as
/// three little-endian `i16` (L*, u*, v* in Q6), 6 bytes a value.
fn luv565_table() -> Vec<u8> {
    use protogist::conspicuity::LUV_TABLES;
    (0..=u16::MAX)
        .flat_map(|v| LUV_TABLES.convert(rgb565::expand_rgb565(v)).to_bits())
        .flat_map(i16::to_le_bytes)
        .collect()
}

/// Classes of the benchmark networks.
const BENCH_CLASSES: u16 = 10;

/// A `PGML` v1 blob (docs/MODEL_FORMAT.md; no symmetry section) of a 720 x `hidden` x 10
/// network: int8 weights uniform in −127..=127 and small biases from
/// `protogist::rng::SplitMix64` seeded with `hidden`; every channel
/// requantised by 2^−5 (multiplier 2^30, shift −4), zero templates, Δ 0.
fn bench_blob(hidden: u16) -> Vec<u8> {
    use protogist::mlp::blob::*;
    let (d, h, k) = (720u16, hidden, BENCH_CLASSES);
    let names: Vec<String> = (0..k).map(|c| format!("c{c}")).collect();
    let names_len: usize = names.iter().map(|n| 1 + n.len()).sum();
    let mut rng = protogist::rng::SplitMix64::new(u64::from(hidden));
    let mut b = Vec::new();
    b.extend_from_slice(&MAGIC);
    b.extend_from_slice(&VERSION_1.to_le_bytes());
    b.extend_from_slice(&[INPUT_I4F12, WEIGHTS_I8_PER_CHANNEL, HIDDEN_U8, OUTPUT_U16]);
    for n in [d, h, k] {
        b.extend_from_slice(&n.to_le_bytes());
    }
    // Input: I4F12 raw times 2^-7 (±3 maps to ±96; beyond ±4, clamped).
    b.extend_from_slice(&(1i32 << 30).to_le_bytes());
    b.extend_from_slice(&(-6i32).to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes());
    b.extend_from_slice(&(names_len as u32).to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes());
    for _ in 0..(h + k) {
        b.extend_from_slice(&(1i32 << 30).to_le_bytes());
        b.extend_from_slice(&(-4i32).to_le_bytes());
    }
    for _ in 0..(h + k) {
        b.extend_from_slice(&rng.range(-4096, 4096).to_le_bytes());
    }
    for _ in 0..(usize::from(h) * usize::from(d) + usize::from(k) * usize::from(h)) {
        // Excess-128 bytes of weights in -127..=127.
        b.push((rng.range(-127, 127) + 128) as u8);
    }
    b.resize(b.len() + 2 * usize::from(k) * usize::from(k), 0);
    for n in &names {
        b.push(n.len() as u8);
        b.extend_from_slice(n.as_bytes());
    }
    let crc = crc32(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

/// The linker script of the memory map: mps2-an386's; with the `f405`
/// feature QEMU netduinoplus2's STM32F405; with `f405-board` the real
/// part's (`memory-f405.x`).
fn memory_map() -> &'static str {
    if env::var_os("CARGO_FEATURE_F405_BOARD").is_some() {
        "memory-f405.x"
    } else if env::var_os("CARGO_FEATURE_F405").is_some() {
        "memory-f405-qemu.x"
    } else {
        "memory.x"
    }
}

/// The bench firmware's map: mps2-an386's 4 MB of code SSRAM
/// (`memory-bench.x`); with the `f405` features, the product's (the bench
/// is not built for the F405).
fn bench_memory_map() -> &'static str {
    if env::var_os("CARGO_FEATURE_F405").is_some() {
        memory_map()
    } else {
        "memory-bench.x"
    }
}

/// The grey tables of `src/stereo_camera.rs` (`GREY565_R`, `_G`, `_B`):
/// core's `grey8` of each channel value of an RGB565 pixel, expanded as
/// the frames expand it, alone. `grey8` is a sum of one product per
/// channel, so a pixel's grey is the sum of its three entries.
fn grey565_tables() -> String {
    use protogist::image::Rgb8;
    use protogist::stereo::phase::grey8;
    let channel = |name: &str, bits: u32, shift: u32, pick: fn(Rgb8) -> Rgb8| {
        let values: Vec<String> = (0..1u16 << bits)
            .map(|c| grey8(pick(rgb565::expand_rgb565(c << shift))).to_string())
            .collect();
        format!(
            "static GREY565_{name}: [i32; {}] = [{}];\n",
            1u32 << bits,
            values.join(", ")
        )
    };
    [
        channel("R", 5, 11, |p| Rgb8::new(p.r, 0, 0)),
        channel("G", 6, 5, |p| Rgb8::new(0, p.g, 0)),
        channel("B", 5, 0, |p| Rgb8::new(0, 0, p.b)),
    ]
    .concat()
}

fn main() {
    for map in [
        "memory.x",
        "memory-bench.x",
        "memory-f405.x",
        "memory-f405-qemu.x",
    ] {
        println!("cargo:rerun-if-changed={map}");
    }
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=src/rgb565.rs");
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    for h in [256u16, 2000] {
        fs::write(out.join(format!("mlp_bench_{h}.bin")), bench_blob(h))
            .expect("write a benchmark network to OUT_DIR");
    }
    fs::write(out.join("luv565.bin"), luv565_table())
        .expect("write the RGB565 CIELUV table to OUT_DIR");
    fs::write(out.join("grey565.rs"), grey565_tables())
        .expect("write the RGB565 grey tables to OUT_DIR");
    let target = env::var("TARGET").unwrap_or_default();
    if !target.starts_with("thumb") {
        return;
    }
    // cortex-m-rt's link.x includes `memory.x` by that name: each binary
    // gets its own directory holding its map as `memory.x`, searched first.
    for (bin, map) in [
        ("firmware-sim", memory_map()),
        ("panic-probe", memory_map()),
        ("bench", bench_memory_map()),
    ] {
        let dir = out.join(format!("map-{bin}"));
        fs::create_dir_all(&dir).expect("create a memory map directory in OUT_DIR");
        fs::copy(map, dir.join("memory.x")).expect("copy the memory map to OUT_DIR");
        println!("cargo:rustc-link-arg-bin={bin}=-L{}", dir.display());
    }
    // cortex-m-rt's link.x includes memory.x; gcc must not add its own crt0.
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-nostartfiles");
}
