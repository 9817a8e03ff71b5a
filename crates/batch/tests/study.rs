//! A study end to end through the library: outputs, rows, failures, resuming.

use std::collections::BTreeMap;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use glint_batch::{
    discover, finish, run_job, run_local, Discover, Item, LocalOptions, Outcome, Row, Spec, Status,
    RESULTS_FILE, ROW_FILE,
};
use glint_io::{nifti, Endian};
use glint_render::{Phantom, ReadOptions, Renderer, Scene, View};

/// Writes `n` small phantom volumes (of growing size, so they differ) and a broken
/// file into `dir`.
fn study(dir: &Path, n: usize) {
    for i in 0..n {
        let vol = Phantom::SheppLogan.volume(20 + 2 * i).unwrap();
        let path = dir.join(format!("vol{i}.nii.gz"));
        nifti::write(&path, &vol, true, Endian::Little).unwrap();
    }
    std::fs::write(dir.join("broken.nii"), b"this is not a NIfTI file").unwrap();
}

fn spec() -> Spec {
    let scene = Scene {
        size: [24, 20],
        ..Scene::default()
    };
    Spec::new(
        scene,
        vec![View::Left, View::Anterior, View::Superior],
        true,
    )
}

fn run(items: &[Item], spec: &Spec, out: &Path, force: bool) -> Vec<Outcome> {
    let options = LocalOptions {
        jobs: 2,
        force,
        ..LocalOptions::default()
    };
    run_local(items, spec, out, &options, &|_| {}).unwrap()
}

/// Every file below `dir` with its inode: a file rewritten atomically gets a new one.
fn inodes(dir: &Path) -> BTreeMap<PathBuf, u64> {
    let mut files = BTreeMap::new();
    for entry in walk(dir) {
        files.insert(entry.clone(), std::fs::metadata(&entry).unwrap().ino());
    }
    files
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG", "{}", path.display());
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn a_study_makes_every_output_and_one_failed_row() {
    let data = tempfile::tempdir().unwrap();
    study(data.path(), 3);
    let out = tempfile::tempdir().unwrap();
    let items = discover(&[data.path().into()], &Discover::default()).unwrap();
    let spec = spec();
    let outcomes = run(&items, &spec, out.path(), false);
    assert!(outcomes.iter().all(|o| !o.skipped));
    let rows: Vec<Row> = outcomes.into_iter().map(|o| o.row).collect();
    let summary = finish(out.path(), &rows).unwrap();
    assert_eq!((summary.ok, summary.failed), (3, 1));

    let broken = rows.iter().find(|r| r.id == "broken").unwrap();
    assert_eq!(broken.status, Status::Failed);
    let err = broken.error.as_deref().unwrap();
    assert!(err.contains("broken.nii") && !err.contains('\n'), "{err}");
    assert!(broken.checksum.is_some() && broken.outputs.is_none());
    // Its folder holds the row only.
    let left: Vec<_> = walk(&out.path().join("broken"));
    assert_eq!(left, [out.path().join("broken").join(ROW_FILE)]);

    for row in rows.iter().filter(|r| r.status == Status::Ok) {
        let o = row.outputs.as_ref().unwrap();
        // Three 24x20 views side by side; three 24x20 slices.
        assert_eq!(png_size(&out.path().join(&o.mosaic)), (72, 20));
        assert_eq!(
            png_size(&out.path().join(o.slices.as_ref().unwrap())),
            (72, 20)
        );
        let scene = Scene::load(&out.path().join(&o.scene)).unwrap();
        assert_eq!(scene.camera.view, View::Left);
        assert!(
            scene.lobe.n.is_some(),
            "the resolved scene names its choices"
        );
        let v = row.volume.as_ref().unwrap();
        assert!(v.window.is_some() && v.dims[0] >= 20);
        assert!(row.seconds.as_ref().unwrap().total > 0.0);
        assert_eq!(
            row.checksum,
            Some(glint_batch::checksum(Path::new(&row.input)).unwrap())
        );
    }

    // The table: one line per row, sorted by id, parsing back to the rows.
    let table = std::fs::read_to_string(out.path().join(RESULTS_FILE)).unwrap();
    let back: Vec<Row> = table
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let mut sorted = rows.clone();
    sorted.sort_by(|a, b| a.id.cmp(&b.id));
    assert_eq!(back, sorted);
    // No temporary file anywhere.
    assert!(walk(out.path()).iter().all(|p| !p
        .file_name()
        .unwrap()
        .to_string_lossy()
        .starts_with(".tmp")));
}

#[test]
fn a_mosaic_tile_is_the_render_of_its_view() {
    let data = tempfile::tempdir().unwrap();
    study(data.path(), 1);
    let out = tempfile::tempdir().unwrap();
    let items = discover(&[data.path().join("vol0.nii.gz")], &Discover::default()).unwrap();
    let spec = spec();
    let row = run_job(&items[0], &spec, out.path(), false).row;
    assert_eq!(row.status, Status::Ok, "{:?}", row.error);
    // The superior view rendered on its own, as `glint render --view superior` does.
    let scene = spec.scene_for(&items[0].path, View::Superior).unwrap();
    let mut renderer = Renderer::open(&scene, &ReadOptions::default()).unwrap();
    let alone = renderer.render(&scene, &|_| {}).unwrap().image;
    let mosaic = std::fs::read(out.path().join(row.outputs.unwrap().mosaic)).unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(mosaic));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    let srgb = alone.encode_srgb(glint_render::Depth::Eight);
    let (w, h) = (alone.width as usize, alone.height as usize);
    for y in 0..h {
        let tile = &buf[(y * 3 * w + 2 * w) * 3..(y * 3 * w + 3 * w) * 3];
        assert_eq!(tile, &srgb[y * w * 3..(y + 1) * w * 3], "row {y}");
    }
}

#[test]
fn a_rerun_makes_nothing_and_a_change_makes_only_what_changed() {
    let data = tempfile::tempdir().unwrap();
    study(data.path(), 3);
    let out = tempfile::tempdir().unwrap();
    let items = discover(&[data.path().into()], &Discover::default()).unwrap();
    let spec = spec();
    let rows: Vec<Row> = run(&items, &spec, out.path(), false)
        .into_iter()
        .map(|o| o.row)
        .collect();
    finish(out.path(), &rows).unwrap();
    let before = inodes(out.path());

    // Again: the good inputs are skipped, the broken one is tried again and fails the
    // same way; no file is rewritten.
    let again = run(&items, &spec, out.path(), false);
    let skipped: Vec<&str> = again
        .iter()
        .filter(|o| o.skipped)
        .map(|o| o.row.id.as_str())
        .collect();
    assert_eq!(skipped, ["vol0", "vol1", "vol2"]);
    let rows2: Vec<Row> = again.into_iter().map(|o| o.row).collect();
    assert_eq!(rows2, rows);
    finish(out.path(), &rows2).unwrap();
    assert_eq!(inodes(out.path()), before, "a rerun rewrote files");

    // One input's bytes change: only it is made again.
    let vol = Phantom::Head.volume(22).unwrap();
    nifti::write(&data.path().join("vol1.nii.gz"), &vol, true, Endian::Little).unwrap();
    let third = run(&items, &spec, out.path(), false);
    let made: Vec<&str> = third
        .iter()
        .filter(|o| !o.skipped && o.row.status == Status::Ok)
        .map(|o| o.row.id.as_str())
        .collect();
    assert_eq!(made, ["vol1"]);

    // Another spec makes everything again; so does force.
    let other = Spec::new(spec.scene.clone(), vec![View::Right], false);
    assert!(run(&items, &other, out.path(), false)
        .iter()
        .all(|o| !o.skipped));
    assert!(run(&items, &other, out.path(), true)
        .iter()
        .all(|o| !o.skipped));
    // Without --slices the old slices are gone and not listed.
    assert!(!out.path().join("vol0/slices.png").exists());

    // An output deleted by hand is made again.
    std::fs::remove_file(out.path().join("vol2/mosaic.png")).unwrap();
    let fourth = run(&items, &other, out.path(), false);
    let vol2 = fourth.iter().find(|o| o.row.id == "vol2").unwrap();
    assert!(!vol2.skipped && out.path().join("vol2/mosaic.png").is_file());
}

#[test]
fn a_missing_file_and_a_file_that_breaks_after_a_good_run_fail_cleanly() {
    let data = tempfile::tempdir().unwrap();
    study(data.path(), 1);
    let out = tempfile::tempdir().unwrap();
    let missing = data.path().join("missing.nii.gz");
    let items = discover(
        &[data.path().join("vol0.nii.gz"), missing.clone()],
        &Discover::default(),
    )
    .unwrap();
    let spec = spec();
    let outcomes = run(&items, &spec, out.path(), false);
    let gone = &outcomes[1].row;
    assert_eq!(
        (gone.status, gone.checksum.as_deref()),
        (Status::Failed, None)
    );
    let err = gone.error.as_deref().unwrap();
    assert!(
        err.contains("missing.nii.gz") && err.contains("No such file"),
        "{err}"
    );

    // vol0 becomes garbage: its old outputs go, its row says why.
    std::fs::write(data.path().join("vol0.nii.gz"), b"garbage").unwrap();
    let outcomes = run(&items, &spec, out.path(), false);
    assert_eq!(outcomes[0].row.status, Status::Failed);
    assert_eq!(
        walk(&out.path().join("vol0")),
        [out.path().join("vol0").join(ROW_FILE)]
    );
}

#[test]
fn leftovers_of_a_killed_job_are_removed() {
    let data = tempfile::tempdir().unwrap();
    study(data.path(), 1);
    let out = tempfile::tempdir().unwrap();
    let items = discover(&[data.path().join("vol0.nii.gz")], &Discover::default()).unwrap();
    let dir = out.path().join("vol0");
    std::fs::create_dir_all(&dir).unwrap();
    // What write_atomic leaves when its process is killed before the rename.
    std::fs::write(dir.join(".tmpAbC123"), b"half a png").unwrap();
    let row = run_job(&items[0], &spec(), out.path(), false).row;
    assert_eq!(row.status, Status::Ok);
    assert!(!dir.join(".tmpAbC123").exists());
}
