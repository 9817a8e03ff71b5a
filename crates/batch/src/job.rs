//! The job of one input: its views rendered by one renderer, its mosaic, slices,
//! resolved scene and row written atomically, or one failed row.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use glint_io::one_line;
use glint_render::{Depth, Input, RenderError, Renderer, Scene};

use crate::picture::{mosaic, mosaic_exr, slices, Window, MOSAIC_EXR_FILE};
use crate::row::{Outputs, Row, Seconds, Status, VolumeInfo};
use crate::{checksum, os_error, BatchError, Item, Spec};

/// The name of an input's row in its output folder, written after its other files:
/// a folder with a row whose outputs exist is a finished input.
pub const ROW_FILE: &str = "row.json";

/// The names of an input's other files in its output folder.
const MOSAIC_FILE: &str = "mosaic.png";
const SLICES_FILE: &str = "slices.png";
const SCENE_FILE: &str = "scene.json";

/// What a job did.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// The input's row.
    pub row: Row,
    /// Whether the outputs were already there (same checksum, same spec) and nothing
    /// was rendered.
    pub skipped: bool,
}

/// Makes one input's outputs in `out/<id>/`: reads the input once, renders every view
/// of `spec` with one renderer (the field built and the transfer function classified
/// once), writes the mosaic, the slices (if asked) and the first view's resolved scene,
/// then `row.json`, each atomically. Unless `force`, an input whose `row.json` says it
/// was made from the same bytes with the same spec, and whose outputs exist, is not
/// made again (its row is returned, `skipped`).
///
/// Never fails: an error (a missing or bad file, a failed render, a full disk, even a
/// panic) gives a failed row with its one line, and the folder then holds no output
/// but the row. Idempotent: running it again (after its process was killed, say)
/// writes the same files, after removing the temporary files a killed run left.
pub fn run_job(item: &Item, spec: &Spec, out: &Path, force: bool) -> Outcome {
    let views: Vec<String> = spec.views.iter().map(|v| v.name().to_string()).collect();
    let dir = out.join(&item.id);
    let key = match spec.key() {
        Ok(k) => k,
        Err(e) => {
            let row = Row::failed(item, "", &views, None, one_line(&e));
            return Outcome {
                row,
                skipped: false,
            };
        }
    };
    let attempt = catch_unwind(AssertUnwindSafe(|| make(item, spec, &key, &dir, force)));
    let (row, skipped) = match attempt {
        Ok(Ok(done)) => done,
        Ok(Err((checksum, err))) => (
            Row::failed(item, &key, &views, checksum, one_line(&err)),
            false,
        ),
        Err(panic) => {
            let message = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic".into());
            let err = BatchError::Panic(message);
            (Row::failed(item, &key, &views, None, one_line(&err)), false)
        }
    };
    if row.status == Status::Failed {
        remove_outputs(&dir);
    }
    if skipped {
        return Outcome { row, skipped };
    }
    let text = row.to_line() + "\n";
    match write_if_changed(&dir.join(ROW_FILE), text.as_bytes()) {
        Ok(()) => Outcome { row, skipped },
        Err(e) => {
            remove_outputs(&dir);
            let row = Row::failed(item, &key, &views, row.checksum, one_line(&e));
            Outcome {
                row,
                skipped: false,
            }
        }
    }
}

/// An input's error and its checksum when it was read.
type Failure = (Option<String>, BatchError);

/// The job proper: the row of a made (or already made) input.
fn make(
    item: &Item,
    spec: &Spec,
    key: &str,
    dir: &Path,
    force: bool,
) -> Result<(Row, bool), Failure> {
    let start = Instant::now();
    let fail = |checksum: &Option<String>| {
        let checksum = checksum.clone();
        move |e: BatchError| (checksum, e)
    };
    std::fs::create_dir_all(dir).map_err(|e| (None, os_error(dir, e)))?;
    remove_temporaries(dir);
    let sum = checksum(&item.path).map_err(|e| (None, e))?;
    let mut seconds = Seconds {
        checksum: start.elapsed().as_secs_f64(),
        ..Seconds::default()
    };
    let sum = Some(sum);
    if !force {
        if let Some(done) = finished(item, key, &sum, dir) {
            return Ok((done, true));
        }
    }
    let t = Instant::now();
    let opened = Input::Path(item.path.clone())
        .open_with(&spec.read_options())
        .map_err(|e| fail(&sum)(e.into()))?;
    seconds.read = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let volume = Arc::new(opened.volume);
    let mut renderer = Renderer::from_source(volume.clone(), Some(spec.scene.prefilter))
        .map_err(|e| fail(&sum)(e.into()))?;
    seconds.field = t.elapsed().as_secs_f64();
    let (tiles, scene) =
        render_views(&mut renderer, item, spec, &mut seconds).map_err(|e| fail(&sum)(e))?;
    let t = Instant::now();
    let picture = mosaic(&tiles).map_err(fail(&sum))?;
    let window = if spec.slices {
        Window::of(&volume)
    } else {
        None
    };
    let cuts = match window {
        Some(w) => Some(slices(&volume, scene.size, w).map_err(fail(&sum))?),
        None if spec.slices => {
            return Err((sum, BatchError::Spec("no finite value to slice".into())));
        }
        None => None,
    };
    seconds.slices = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let exr = spec.exr.then_some(&picture);
    let outputs =
        write_outputs(item, dir, (&picture, exr), cuts.as_ref(), &scene).map_err(fail(&sum))?;
    seconds.write = t.elapsed().as_secs_f64();
    seconds.total = start.elapsed().as_secs_f64();
    let row = Row {
        id: item.id.clone(),
        input: item.path.to_string_lossy().into_owned(),
        subject: item.subject.clone(),
        session: item.session.clone(),
        status: Status::Ok,
        checksum: sum,
        spec: key.into(),
        views: spec.views.iter().map(|v| v.name().to_string()).collect(),
        outputs: Some(outputs),
        volume: Some(VolumeInfo {
            dims: volume.dims,
            spacing: volume.spacing,
            window: window.map(|w| [w.lo, w.hi]),
        }),
        seconds: Some(seconds),
        notes: opened.notes,
        error: None,
    };
    // The samples' memory goes to the next input's read (paged in already; a fresh
    // buffer's pages are cleared by the kernel, 9% of a subject's CPU, issue 47).
    drop(renderer);
    if let Ok(volume) = Arc::try_unwrap(volume) {
        glint_io::recycle(volume.samples);
    }
    Ok((row, false))
}

/// Every view of the spec rendered by `renderer` (colour bars drawn as `glint render`
/// draws them); the first view's resolved scene.
fn render_views(
    renderer: &mut Renderer,
    item: &Item,
    spec: &Spec,
    seconds: &mut Seconds,
) -> Result<(Vec<glint_render::Image>, Scene), BatchError> {
    let mut tiles = Vec::with_capacity(spec.views.len());
    let mut first = None;
    for &view in &spec.views {
        let scene = spec.scene_for(&item.path, view)?;
        let mut rendered = renderer.render(&scene, &|_| {})?;
        seconds.classify += rendered.timings.get("classify").as_secs_f64();
        seconds.frames += rendered.timings.get("frame").as_secs_f64();
        if let Some(colors) = &rendered.colors {
            colors.draw_bar(&mut rendered.image);
        }
        tiles.push(rendered.image);
        first.get_or_insert(rendered.scene);
    }
    let scene = first.ok_or_else(|| BatchError::Spec("no view: give at least one".into()))?;
    Ok((tiles, scene))
}

/// Writes the mosaic (and its EXR when given, or removes an old one), the slices (or
/// removes old ones) and the scene.
fn write_outputs(
    item: &Item,
    dir: &Path,
    (picture, exr): (&glint_render::Image, Option<&glint_render::Image>),
    cuts: Option<&glint_render::Image>,
    scene: &Scene,
) -> Result<Outputs, BatchError> {
    let png = |img: &glint_render::Image| {
        img.encode_png(Depth::Eight)
            .map_err(|e| BatchError::Render(RenderError::Encode(e)))
    };
    write_if_changed(&dir.join(MOSAIC_FILE), &png(picture)?)?;
    match exr {
        Some(p) => write_if_changed(&dir.join(MOSAIC_EXR_FILE), &mosaic_exr(p)?)?,
        None => remove_file(&dir.join(MOSAIC_EXR_FILE)),
    }
    match cuts {
        Some(c) => write_if_changed(&dir.join(SLICES_FILE), &png(c)?)?,
        None => remove_file(&dir.join(SLICES_FILE)),
    }
    let json = scene.with_absolute_paths()?.to_json()? + "\n";
    write_if_changed(&dir.join(SCENE_FILE), json.as_bytes())?;
    let rel = |name: &str| format!("{}/{name}", item.id);
    Ok(Outputs {
        mosaic: rel(MOSAIC_FILE),
        slices: cuts.map(|_| rel(SLICES_FILE)),
        scene: rel(SCENE_FILE),
    })
}

/// The row of an input already made from the same bytes and spec, whose outputs all
/// exist.
fn finished(item: &Item, key: &str, sum: &Option<String>, dir: &Path) -> Option<Row> {
    let text = std::fs::read_to_string(dir.join(ROW_FILE)).ok()?;
    let row: Row = serde_json::from_str(&text).ok()?;
    let out = dir.parent()?;
    let same = row.status == Status::Ok
        && row.id == item.id
        && row.input == item.path.to_string_lossy()
        && row.spec == key
        && &row.checksum == sum;
    (same && row.output_paths().iter().all(|p| out.join(p).is_file())).then_some(row)
}

/// Writes `bytes` to `path` atomically, unless the file already holds them (a rerun
/// that makes the same file leaves it untouched).
pub(crate) fn write_if_changed(path: &Path, bytes: &[u8]) -> Result<(), BatchError> {
    if std::fs::read(path).is_ok_and(|old| old == bytes) {
        return Ok(());
    }
    glint_io::write_atomic(path, |w| w.write_all(bytes))?;
    Ok(())
}

/// Removes an input's outputs (after a failure: the folder keeps only the row).
fn remove_outputs(dir: &Path) {
    for name in [MOSAIC_FILE, MOSAIC_EXR_FILE, SLICES_FILE, SCENE_FILE] {
        remove_file(&dir.join(name));
    }
}

/// Removes a file if it is there (a file that cannot be removed stays; its input's
/// row does not list it).
fn remove_file(path: &Path) {
    let _ = std::fs::remove_file(path);
}

/// Removes the temporary files an interrupted job left in its folder
/// ([`glint_io::write_atomic`] writes `.tmp*` files beside the target and renames
/// them; a killed process leaves them).
fn remove_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        if entry.file_name().to_string_lossy().starts_with(".tmp") {
            remove_file(&entry.path());
        }
    }
}
