//! The model shipped in the repository (`host/data/shapes_model.bin`) and
//! the categorisation of object masks with it (the demo, issue 5 §9).
//!
//! The model is made by two seeded project commands (docs/CLASSIFY.md,
//! "Shipped model"), checked bit for bit by `host/tests/shipped_model.rs`;
//! it is trained on the masks core's pipeline segments
//! ([`super::pipeline_data`]):
//!
//! ```text
//! protogist gen-shapes --out shapes --classes 19 --per-class 1000 --seed 1 --size 64
//! protogist train --dataset shapes --hidden 256 --epochs 600 --seed 1 --gamma 0.5 \
//!                 --test-fraction 0.1 --through-pipeline --views 2 --with-clean \
//!                 --mirror-images --out host/data/shapes_model.bin
//! ```

use super::dataset::shape_inputs;
use super::quant::shape_elems;
use super::ClassifyError;
use crate::error::Result;
use protogist::mlp::{forward, identify, top_k, Identity, Model, Ranked, Scratch, TOP_K};

/// The shipped model blob.
pub static SHIPPED_MODEL: &[u8] = include_bytes!("../../data/shapes_model.bin");

/// What the classifier says about one object.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Categorisation {
    /// Identification with the model's Δ (or the unknown class).
    pub identity: Identity,
    /// The best classes, best first (up to [`TOP_K`]).
    pub ranked: Vec<Ranked>,
}

/// Categorises a mask (non-zero = object) with `model`: `None` when the
/// mask is empty or has no shape (zero variance).
///
/// # Errors
/// A size the core rejects; a model whose input is not a shape vector.
pub fn categorise_mask(
    model: &Model<'_>,
    mask: &[u8],
    width: usize,
    height: usize,
) -> Result<Option<Categorisation>> {
    let Some((_, raw)) = shape_inputs(mask, width, height)? else {
        return Ok(None);
    };
    let (d, h, k) = (model.inputs(), model.hidden(), model.classes());
    let (mut xi, mut hi, mut yo) = (
        vec![0u32; protogist::mlp::packed_len(d, h)],
        vec![0u8; h],
        vec![0u16; k],
    );
    let mut s = Scratch {
        input: &mut xi,
        hidden: &mut hi,
        output: &mut yo,
    };
    let out = forward(model, &shape_elems(&raw), &mut s).map_err(ClassifyError::from)?;
    let mut ranked = [Ranked::default(); TOP_K];
    let n = top_k(model, out, &mut ranked).map_err(ClassifyError::from)?;
    let (identity, _) = identify(model, out).map_err(ClassifyError::from)?;
    Ok(Some(Categorisation {
        identity,
        ranked: ranked.get(..n).unwrap_or(&[]).to_vec(),
    }))
}

/// One summary line: `ellipse (0.993) | top 5: ellipse 0.993, ...`.
pub fn describe(model: &Model<'_>, c: &Categorisation) -> String {
    let name = |k: u16| model.class_name(usize::from(k)).unwrap_or("?");
    let id = match c.identity {
        Identity::Known(k) => name(k).to_string(),
        Identity::Unknown => format!(
            "unknown (best below Δ = {:.3})",
            f64::from(model.delta_q16()) / 65536.0
        ),
    };
    let top: Vec<String> = c
        .ranked
        .iter()
        .map(|r| format!("{} {:.3}", name(r.class), f64::from(r.score) / 65536.0))
        .collect();
    format!("{id} | top {}: {}", c.ranked.len(), top.join(", "))
}

/// Appends one `category, object k<label>` line per detected object of
/// `seg`: its identity and top 5.
///
/// # Errors
/// A malformed shipped model (a build defect), or as [`categorise_mask`].
pub fn summarise_objects(
    seg: &crate::stages::SegmentResult,
    label: &str,
    summary: &mut crate::summary::Summary,
) -> Result<()> {
    let path = std::path::Path::new("host/data/shapes_model.bin");
    let model = Model::parse(SHIPPED_MODEL)
        .map_err(|e| super::model::bad_model(path, super::quant::model_error(e)))?;
    for (k, d) in seg.report.objects.iter().enumerate() {
        if d.area == 0 {
            continue;
        }
        let line = match categorise_mask(&model, &seg.mask_u8(k), seg.width, seg.height)? {
            Some(c) => describe(&model, &c),
            None => "no shape (degenerate mask)".into(),
        };
        summary.push(format!("category, object {k}{label}"), line);
    }
    Ok(())
}

/// A class name without its leading ordinal: `04_circle` reads `circle`.
pub fn display_name(name: &str) -> &str {
    match name.split_once('_') {
        Some((n, rest)) if !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()) => rest,
        _ => name,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn display_names_drop_the_ordinal_only() {
        for (name, shown) in [
            ("04_circle", "circle"),
            ("10_crescent_moon", "crescent_moon"),
            ("circle", "circle"),
            ("_x", "_x"),
            ("a1_b", "a1_b"),
        ] {
            assert_eq!(super::display_name(name), shown);
        }
    }
}
