//! Training data as the pipeline produces it (issue 20 §3, `protogist
//! train --through-pipeline`): each silhouette of an image-folder dataset
//! is rendered into `views` seeded stereo scenes ([`render_given`]), core's
//! pipeline runs on each pair as the product runs it, and the mask matched
//! to that silhouette (box IoU ≥ 0.5, the matching of `gist-eval`) is kept,
//! labelled with the silhouette's class.
//!
//! **Scenes.** 160x120, the size of `gen-scenes` and of the bundled
//! decoder tables. The silhouette is the scene's first object (so it is
//! always tried first), and 0 to 3 other objects join it (the count drawn
//! uniformly in 1..=4, as `gen-scenes` draws it), silhouettes of other
//! classes from the training split of the same dataset: the pipeline then
//! meets the neighbours, merges and occlusions of the scenes it is
//! measured on, and the dataset needs nothing but its own silhouettes. The
//! other objects' masks are not kept.
//!
//! **Pipeline.** [`PipelineParams::DEFAULT`] searching K = 4 objects with
//! the largest disparity of the width ([`default_max_disp`]), the
//! parameters `gist-eval --mode core` uses. A kept sample's shape vector
//! is the pipeline's own (`Frame::shape`), so training sees the bits
//! inference sees. The pipeline is given the shipped model only because it
//! needs one: masks and shape vectors do not depend on the classifier.
//!
//! **Seeds.** Scene `v` of silhouette `key` draws from a stream keyed by
//! the seed, a hash of `key` and `v`: a silhouette's scenes depend neither
//! on the other files of the dataset nor on the thread count.

use super::dataset::{mask_of, Dataset, Sample};
use super::mlp::SplitMix;
use super::rules::z_normalise;
use crate::error::{HostError, Result};
use crate::gist::score::match_boxes;
use crate::product::{default_max_disp, tables_for};
use crate::scenes::given::{render_given, GivenObject};
use crate::scenes::render::{mix64, RenderedScene};
use crate::scenes::{BoxPx, SceneParams};
use image::GrayImage;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use protogist::image::ImageView;
use protogist::pipeline::{workspace_words, Pipeline, PipelineParams};
use rayon::prelude::*;
use std::path::Path;

/// The scenes' size and object counts.
pub const SCENES: SceneParams = SceneParams {
    width: 160,
    height: 120,
    classes: 0,
    objects: (1, 4),
};

/// Objects the pipeline searches per scene (K).
pub const SEARCHED: u8 = 4;

/// Most views per silhouette.
pub const MAX_VIEWS: usize = 64;

/// The pipeline's parameters for the training scenes.
pub fn pipeline_params() -> PipelineParams {
    PipelineParams::DEFAULT
        .with_objects(SEARCHED)
        .with_max_disp(default_max_disp(SCENES.width as usize))
}

/// What a harvest found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Harvest {
    /// The kept masks: `(index into the dataset's samples, sample)`; the
    /// sample's key is the silhouette's with `#v` and the view appended.
    pub samples: Vec<(usize, Sample)>,
    /// Scenes rendered.
    pub scenes: usize,
    /// Scenes in which the silhouette found a place.
    pub placed: usize,
}

impl Harvest {
    /// Share of the placed silhouettes whose mask was matched.
    pub fn matched_rate(&self) -> f64 {
        self.samples.len() as f64 / self.placed.max(1) as f64
    }
}

/// FNV-1a of `s`: a stable hash (not `std`'s, which may change).
fn fnv1a(s: &str) -> u64 {
    s.bytes().fold(0xCBF2_9CE4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01B3)
    })
}

/// The stream of scene `view` of silhouette `key`.
pub fn scene_stream(seed: u64, key: &str, view: usize) -> u64 {
    mix64(mix64(seed ^ 0x7452_4149_4E50_4950) ^ mix64(fnv1a(key)) ^ view as u64)
}

/// The masks (255 on 0) of the dataset's samples, read again from `dir`.
///
/// # Errors
/// Decoding and I/O errors.
pub fn load_masks(dir: &Path, ds: &Dataset) -> Result<Vec<GrayImage>> {
    ds.samples
        .par_iter()
        .map(|s| {
            let img = crate::io::load_image(&dir.join(&s.key))?;
            let (m, w, h) = mask_of(&img);
            let raw = m.into_iter().map(|v| v * 255).collect();
            GrayImage::from_raw(w as u32, h as u32, raw).ok_or_else(|| HostError::Dataset {
                path: dir.join(&s.key),
                reason: "its mask does not match its size".into(),
            })
        })
        .collect()
}

/// The other objects of a scene: up to `n` silhouettes of distinct classes
/// other than `class`, from `by_class` (indices per class).
fn companions(rng: &mut SplitMix, by_class: &[Vec<usize>], class: usize, n: usize) -> Vec<usize> {
    let mut classes: Vec<usize> = (0..by_class.len())
        .filter(|&c| c != class && !by_class[c].is_empty())
        .collect();
    let mut out = Vec::new();
    while out.len() < n && !classes.is_empty() {
        let c = classes.swap_remove((rng.next_u64() % classes.len() as u64) as usize);
        let pool = &by_class[c];
        out.push(pool[(rng.next_u64() % pool.len() as u64) as usize]);
    }
    out
}

/// One scene: the pipeline's shape vector (`I4F12` bits) of the mask
/// matched to object 0, `None` when it was not placed or not matched.
fn scene_mask(
    pipeline: &Pipeline<'_>,
    workspace: &mut [u64],
    scene: &RenderedScene,
) -> Result<Option<Vec<i16>>> {
    let (w, h) = (SCENES.width as usize, SCENES.height as usize);
    if scene.sources.first() != Some(&0) {
        return Ok(None);
    }
    let (left, right) = (
        crate::io::to_core_rgb(&scene.left),
        crate::io::to_core_rgb(&scene.right),
    );
    let frame = pipeline.run(
        &ImageView::packed(&left, w, h)?,
        &ImageView::packed(&right, w, h)?,
        workspace,
    )?;
    let mut boxes = Vec::new();
    let mut shapes = Vec::new();
    for o in frame.objects() {
        let (Some(mask), Some(shape)) = (frame.mask(o), frame.shape(o)) else {
            continue;
        };
        let Some(b) = BoxPx::of(w as u32, h as u32, |x, y| mask.get(x as usize, y as usize)) else {
            continue;
        };
        boxes.push(b);
        shapes.push(shape.iter().map(|e| e.to_bits()).collect::<Vec<i16>>());
    }
    let truth: Vec<BoxPx> = scene.objects.iter().map(|o| o.bbox).collect();
    Ok(match_boxes(&boxes, &truth)
        .into_iter()
        .find(|m| m.object == 0)
        .and_then(|m| shapes.get(m.detection).cloned()))
}

/// Renders each of `targets` (indices into `ds.samples`, with `masks` their
/// silhouettes) into `views` scenes beside silhouettes of `companions`, runs
/// the pipeline and keeps the matched masks, in target then view order.
///
/// # Errors
/// [`HostError::InvalidArgument`] for `views` out of range; the pipeline's
/// or the renderer's errors.
pub fn harvest(
    ds: &Dataset,
    masks: &[GrayImage],
    targets: &[usize],
    companion_pool: &[usize],
    views: usize,
    seed: u64,
    progress: bool,
) -> Result<Harvest> {
    if !(1..=MAX_VIEWS).contains(&views) {
        return Err(HostError::InvalidArgument {
            name: "views",
            reason: format!("{views} is outside 1..={MAX_VIEWS}"),
        });
    }
    let params = pipeline_params();
    let tables = tables_for(&params)?;
    let refs: Vec<&[u8]> = tables.iter().map(Vec::as_slice).collect();
    let pipeline = Pipeline::new(&params, &refs, super::shipped::SHIPPED_MODEL)?;
    let words = workspace_words(SCENES.width as usize, SCENES.height as usize, &params);
    let mut by_class = vec![Vec::new(); ds.classes.len()];
    for &i in companion_pool {
        by_class[ds.samples[i].label].push(i);
    }
    let jobs: Vec<(usize, usize)> = targets
        .iter()
        .flat_map(|&t| (0..views).map(move |v| (t, v)))
        .collect();
    let bar = if progress {
        ProgressBar::new(jobs.len() as u64)
    } else {
        ProgressBar::with_draw_target(Some(jobs.len() as u64), ProgressDrawTarget::hidden())
    };
    bar.set_style(
        ProgressStyle::with_template("scenes {bar:40} {pos}/{len} [{elapsed}<{eta}]")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let found: Vec<(bool, Option<Sample>)> = jobs
        .par_iter()
        .map_init(
            || vec![0u64; words],
            |ws, &(t, v)| {
                let s = &ds.samples[t];
                let stream = scene_stream(seed, &s.key, v);
                let mut rng = SplitMix::new(mix64(stream ^ 0xC0));
                let others = (rng.next_u64() % 4) as usize;
                let mut given = vec![GivenObject {
                    class: &ds.classes[s.label],
                    mask: &masks[t],
                }];
                for c in companions(&mut rng, &by_class, s.label, others) {
                    given.push(GivenObject {
                        class: &ds.classes[ds.samples[c].label],
                        mask: &masks[c],
                    });
                }
                let scene = render_given(&SCENES, stream, &given)?;
                let placed = scene.sources.first() == Some(&0);
                let kept = scene_mask(&pipeline, ws, &scene)?.and_then(|shape| {
                    let mut x: Vec<f32> = shape
                        .iter()
                        .map(|&b| protogist::shape::ShapeElem::from_bits(b).to_num::<f32>())
                        .collect();
                    z_normalise(&mut x).ok().map(|()| Sample {
                        key: format!("{}#v{v}", s.key),
                        label: s.label,
                        x,
                        shape,
                    })
                });
                bar.inc(1);
                Ok((placed, kept))
            },
        )
        .collect::<Result<_>>()?;
    bar.finish_and_clear();
    let mut h = Harvest {
        scenes: jobs.len(),
        ..Harvest::default()
    };
    for (&(t, _), (placed, kept)) in jobs.iter().zip(found) {
        h.placed += usize::from(placed);
        if let Some(s) = kept {
            h.samples.push((t, s));
        }
    }
    Ok(h)
}

/// Checks that every class of `ds` has a kept mask in `h`.
///
/// # Errors
/// [`HostError::Dataset`] naming the first class folder without one.
pub fn check_classes(dir: &Path, ds: &Dataset, h: &Harvest, views: usize) -> Result<()> {
    for (c, name) in ds.classes.iter().enumerate() {
        if !h.samples.iter().any(|(_, s)| s.label == c) {
            let n = ds.samples.iter().filter(|s| s.label == c).count();
            return Err(HostError::Dataset {
                path: dir.join(name),
                reason: format!(
                    "the pipeline found none of its training silhouettes in {views} scene(s) each \
                     ({n} image(s) in the class): its silhouettes may be too thin, too small or \
                     too fragmented to render and segment; train without --through-pipeline, or \
                     with more --views"
                ),
            });
        }
    }
    Ok(())
}

/// Options of `protogist train` for training on the pipeline's masks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::Args)]
pub struct PipelineTraining {
    /// Train on the masks the pipeline segments: each training silhouette
    /// rendered into `--views` seeded stereo scenes, the mask matched to it
    /// kept with its class.
    #[arg(long)]
    pub through_pipeline: bool,
    /// Scenes per silhouette (1..=64).
    #[arg(long, default_value_t = 4, requires = "through_pipeline")]
    pub views: usize,
    /// Also train on the clean training silhouettes.
    #[arg(long, requires = "through_pipeline")]
    pub with_clean: bool,
}

impl PipelineTraining {
    /// The record of a sidecar, `None` without `--through-pipeline`.
    pub fn record(&self) -> Option<PipelineRecord> {
        self.through_pipeline.then_some(PipelineRecord {
            views: self.views,
            with_clean: self.with_clean,
        })
    }
}

/// How a model was trained on pipeline masks, as its sidecar records it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PipelineRecord {
    /// Scenes per silhouette.
    pub views: usize,
    /// Whether the clean training silhouettes were trained on too.
    pub with_clean: bool,
}

/// The pipeline masks of one side of a split (`test` = the held-out
/// silhouettes), companions from the training side.
///
/// # Errors
/// As [`load_masks`] and [`harvest`].
pub fn harvest_split(
    dir: &Path,
    ds: &Dataset,
    is_test: &[bool],
    test: bool,
    rec: &PipelineRecord,
    seed: u64,
    progress: bool,
) -> Result<Harvest> {
    let masks = load_masks(dir, ds)?;
    let pick =
        |t: bool| -> Vec<usize> { (0..ds.samples.len()).filter(|&i| is_test[i] == t).collect() };
    harvest(
        ds,
        &masks,
        &pick(test),
        &pick(false),
        rec.views,
        seed,
        progress,
    )
}

/// The training samples: the kept masks of the training silhouettes, after
/// the clean silhouettes themselves with `with_clean`.
///
/// # Errors
/// As [`harvest_split`] and [`check_classes`].
pub fn training_samples(
    dir: &Path,
    ds: &Dataset,
    is_test: &[bool],
    rec: &PipelineRecord,
    seed: u64,
    progress: bool,
) -> Result<(Vec<Sample>, Harvest)> {
    let h = harvest_split(dir, ds, is_test, false, rec, seed, progress)?;
    check_classes(dir, ds, &h, rec.views)?;
    let mut out: Vec<Sample> = if rec.with_clean {
        ds.samples
            .iter()
            .zip(is_test)
            .filter(|(_, &t)| !t)
            .map(|(s, _)| s.clone())
            .collect()
    } else {
        Vec::new()
    };
    out.extend(h.samples.iter().map(|(_, s)| s.clone()));
    Ok((out, h))
}

/// Top-1 of the int8 `model` on `samples` (the product's ranking: cosine
/// to the blob's class templates), `None` for no sample.
///
/// # Errors
/// A vector the model rejects.
pub fn int8_top1<'s>(
    model: &protogist::mlp::Model<'_>,
    samples: impl IntoIterator<Item = &'s Sample>,
) -> Result<Option<f64>> {
    let (raw, labels): (Vec<Vec<i16>>, Vec<usize>) = samples
        .into_iter()
        .map(|s| (s.shape.clone(), s.label))
        .unzip();
    if raw.is_empty() {
        return Ok(None);
    }
    let scores = super::quant::int_scores(model, &super::quant::int_outputs(model, &raw)?)?;
    let right = scores
        .iter()
        .zip(&labels)
        .filter(|(s, &c)| {
            let f: Vec<f64> = s.iter().map(|&v| f64::from(v)).collect();
            super::rules::ranked(&f).first() == Some(&c)
        })
        .count();
    Ok(Some(right as f64 / raw.len() as f64))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::classify::dataset::{load_dataset, stratified_split};
    use crate::classify::model_cmd::{run_train_with, Features, TrainOptions};
    use crate::classify::shapes::{gen_shapes, GenShapesOptions};

    /// 3 classes of 4 silhouettes, split in half.
    fn dataset(dir: &Path) -> (Dataset, Vec<bool>) {
        gen_shapes(&GenShapesOptions {
            out: dir.to_path_buf(),
            classes: 3,
            per_class: 4,
            seed: 2,
            size: 64,
        })
        .unwrap();
        let ds = load_dataset(dir).unwrap();
        let labels: Vec<usize> = ds.samples.iter().map(|s| s.label).collect();
        let is_test = stratified_split(&labels, 3, 0.5, 1);
        (ds, is_test)
    }

    const REC: PipelineRecord = PipelineRecord {
        views: 2,
        with_clean: false,
    };

    #[test]
    fn harvest_is_seeded_whatever_the_threads_and_keeps_pipeline_vectors() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("shapes");
        let (ds, is_test) = dataset(&dir);
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| harvest_split(&dir, &ds, &is_test, false, &REC, 3, false).unwrap())
        };
        let h = run(1);
        assert_eq!(h, run(2));
        assert_eq!(h.scenes, 6 * 2);
        assert!(h.placed <= h.scenes && h.samples.len() <= h.placed);
        assert!(!h.samples.is_empty(), "some mask is matched");
        for (t, s) in &h.samples {
            assert!(!is_test[*t]);
            assert_eq!(s.label, ds.samples[*t].label);
            assert!(s.key.starts_with(&format!("{}#v", ds.samples[*t].key)));
            assert_eq!((s.x.len(), s.shape.len()), (720, 720));
        }
        // The kept vector is the one the product computes on that scene.
        let masks = load_masks(&dir, &ds).unwrap();
        let (t, s) = &h.samples[0];
        let v: usize = s.key.rsplit("#v").next().unwrap().parse().unwrap();
        let stream = scene_stream(3, &ds.samples[*t].key, v);
        let mut rng = SplitMix::new(mix64(stream ^ 0xC0));
        let n = (rng.next_u64() % 4) as usize;
        let train: Vec<usize> = (0..12).filter(|&i| !is_test[i]).collect();
        let mut by_class = vec![Vec::new(); 3];
        for &i in &train {
            by_class[ds.samples[i].label].push(i);
        }
        let mut given = vec![GivenObject {
            class: &ds.classes[s.label],
            mask: &masks[*t],
        }];
        for c in companions(&mut rng, &by_class, s.label, n) {
            given.push(GivenObject {
                class: &ds.classes[ds.samples[c].label],
                mask: &masks[c],
            });
        }
        let scene = render_given(&SCENES, stream, &given).unwrap();
        let params = pipeline_params();
        let run = crate::product::run_frame(
            &params,
            &tables_for(&params).unwrap(),
            super::super::shipped::SHIPPED_MODEL,
            &crate::io::to_core_rgb(&scene.left),
            &crate::io::to_core_rgb(&scene.right),
            160,
            120,
        )
        .unwrap();
        let want: Vec<f32> = s
            .shape
            .iter()
            .map(|&b| protogist::shape::ShapeElem::from_bits(b).to_num::<f32>())
            .collect();
        assert!(run.objects.iter().any(|o| o.shape == want));
    }

    #[test]
    fn bad_views_and_classes_without_masks_are_typed_errors() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("shapes");
        let (ds, is_test) = dataset(&dir);
        for views in [0, MAX_VIEWS + 1] {
            let rec = PipelineRecord { views, ..REC };
            let e = harvest_split(&dir, &ds, &is_test, false, &rec, 1, false).unwrap_err();
            assert!(e.to_string().contains("--views"), "{e}");
        }
        let e = check_classes(&dir, &ds, &Harvest::default(), 2).unwrap_err();
        assert!(
            matches!(&e, HostError::Dataset { path, .. } if path.ends_with(&ds.classes[0])),
            "{e}"
        );
        assert!(e.to_string().contains("none of its training silhouettes"));
        // Silhouettes that render to nothing (empty masks) are never placed.
        let masks: Vec<GrayImage> = ds.samples.iter().map(|_| GrayImage::new(8, 8)).collect();
        let train: Vec<usize> = (0..12).filter(|&i| !is_test[i]).collect();
        let h = harvest(&ds, &masks, &train, &train, 1, 1, false).unwrap();
        assert_eq!((h.placed, h.samples.len()), (0, 0));
        assert!(check_classes(&dir, &ds, &h, 1).is_err());
    }

    #[test]
    fn views_need_the_pipeline_flag() {
        use clap::Parser;
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            p: PipelineTraining,
        }
        assert!(Cli::try_parse_from(["t", "--views", "3"]).is_err());
        assert!(Cli::try_parse_from(["t", "--with-clean"]).is_err());
        let c = Cli::try_parse_from(["t", "--through-pipeline", "--views", "3"]).unwrap();
        assert_eq!(
            c.p.record(),
            Some(PipelineRecord {
                views: 3,
                with_clean: false
            })
        );
        assert_eq!(Cli::try_parse_from(["t"]).unwrap().p.record(), None);
    }

    #[test]
    fn train_through_the_pipeline_records_it_and_quantize_rebuilds_the_blob() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("shapes");
        dataset(&dir);
        let out = tmp.path().join("m.bin");
        let opts = TrainOptions {
            dataset: dir.clone(),
            hidden: 8,
            epochs: 5,
            out: out.clone(),
            features: Features::Shape,
            test_fraction: 0.5,
            seed: 1,
            gamma: 0.2,
            mirror_images: false,
        };
        let pipe = PipelineTraining {
            through_pipeline: true,
            views: 2,
            with_clean: true,
        };
        let s = run_train_with(&opts, &pipe).unwrap().to_string();
        assert!(s.contains("their pipeline masks"), "{s}");
        let blob = std::fs::read(&out).unwrap();
        let m = protogist::mlp::Model::parse(&blob).unwrap();
        assert!(m
            .meta()
            .ends_with("--through-pipeline --views 2 --with-clean"));
        let (_, file) = crate::classify::model_cmd::load_models(&out).unwrap();
        assert_eq!(file.pipeline, pipe.record());
        let again = tmp.path().join("again.bin");
        crate::classify::quant_cmd::run_quantize(&crate::classify::quant_cmd::QuantizeOptions {
            model: crate::classify::model_cmd::sidecar_path(&out),
            dataset: Some(dir),
            out: Some(again.clone()),
            emit_rust: None,
        })
        .unwrap();
        assert!(
            std::fs::read(&again).unwrap() == blob,
            "quantize rebuilds it"
        );
    }
}
