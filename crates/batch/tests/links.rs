//! Studies laid out as DataLad keeps them: every file a symbolic link into
//! `.git/annex/objects/`, a file never fetched a link to nothing; and links that loop.

use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};

use glint_batch::{discover, run_local, Discover, LocalOptions, Row, Spec, Status};
use glint_io::{nifti, Endian};
use glint_render::{Phantom, Scene, View};

/// A DataLad-like dataset in `root`: subjects 01..03 with their T1w as links into the
/// annex (content present), subject 04's a link to an annex object never fetched.
/// With `bids`, a `dataset_description.json` makes it a BIDS dataset.
fn annex_dataset(root: &Path, bids: bool) {
    if bids {
        std::fs::write(
            root.join("dataset_description.json"),
            br#"{"Name": "annex", "BIDSVersion": "1.9.0"}"#,
        )
        .unwrap();
    }
    for i in 1..=4 {
        let key = format!("MD5E-s100--{i:032}.nii.gz");
        let object = root.join(format!(".git/annex/objects/k{i}/q{i}/{key}/{key}"));
        if i < 4 {
            std::fs::create_dir_all(object.parent().unwrap()).unwrap();
            let vol = Phantom::SheppLogan.volume(16 + 2 * i).unwrap();
            nifti::write(&object, &vol, true, Endian::Little).unwrap();
        }
        let anat = root.join(format!("sub-0{i}/anat"));
        std::fs::create_dir_all(&anat).unwrap();
        // As git-annex writes them: relative, up to the dataset's root.
        let target = format!("../../.git/annex/objects/k{i}/q{i}/{key}/{key}");
        symlink(target, anat.join(format!("sub-0{i}_T1w.nii.gz"))).unwrap();
    }
}

fn rows(inputs: &[PathBuf]) -> Vec<Row> {
    let items = discover(inputs, &Discover::default()).unwrap();
    let scene = Scene {
        size: [16, 16],
        ..Scene::default()
    };
    let spec = Spec::new(scene, vec![View::Left], false);
    let out = tempfile::tempdir().unwrap();
    let mut rows: Vec<Row> =
        run_local(&items, &spec, out.path(), &LocalOptions::default(), &|_| {})
            .unwrap()
            .into_iter()
            .map(|o| o.row)
            .collect();
    rows.sort_by(|a, b| a.id.cmp(&b.id));
    rows
}

/// The done-when of issue 47: three linked subjects rendered, the fourth reported as not
/// present, with the command that fetches it; in a BIDS dataset and in a plain folder.
#[test]
fn an_annex_dataset_renders_what_is_present_and_names_what_is_not() {
    for bids in [true, false] {
        let data = tempfile::tempdir().unwrap();
        annex_dataset(data.path(), bids);
        let rows = rows(&[data.path().into()]);
        assert_eq!(rows.len(), 4, "bids {bids}: {rows:?}");
        for row in &rows[..3] {
            assert_eq!(row.status, Status::Ok, "bids {bids}: {row:?}");
        }
        let missing = &rows[3];
        assert_eq!(missing.status, Status::Failed);
        assert!(missing.id.contains("sub-04"), "{}", missing.id);
        let link = data.path().join("sub-04/anat/sub-04_T1w.nii.gz");
        let error = missing.error.as_deref().unwrap_or_default();
        assert!(
            error.contains(&format!(
                "content not present (git-annex): run `datalad get {}`",
                link.display()
            )),
            "bids {bids}: {error}"
        );
    }
}

/// A link to nothing outside an annex says where it pointed; links that loop back are
/// walked once; a file reached through two links is one input.
#[test]
fn broken_links_and_loops() {
    let data = tempfile::tempdir().unwrap();
    let root = data.path();
    let elsewhere = tempfile::tempdir().unwrap();
    let vol = Phantom::SheppLogan.volume(16).unwrap();
    let real = elsewhere.path().join("subject.nii.gz");
    nifti::write(&real, &vol, true, Endian::Little).unwrap();
    symlink(&real, root.join("a.nii.gz")).unwrap();
    std::fs::create_dir(root.join("site")).unwrap();
    symlink(&real, root.join("site/same.nii.gz")).unwrap();
    symlink("/nowhere/gone.nii.gz", root.join("gone.nii.gz")).unwrap();
    // Two loops: the folder itself, and a parent from below.
    symlink(".", root.join("again")).unwrap();
    symlink("..", root.join("site/up")).unwrap();
    let rows = rows(&[root.into()]);
    let ids: Vec<&str> = rows.iter().map(|r| r.id.as_str()).collect();
    assert_eq!(ids, ["a", "gone"], "{rows:?}");
    assert_eq!(rows[0].status, Status::Ok);
    assert_eq!(rows[1].status, Status::Failed);
    let error = rows[1].error.as_deref().unwrap_or_default();
    assert!(
        error.ends_with(&format!(
            "{}: broken symbolic link to /nowhere/gone.nii.gz",
            root.join("gone.nii.gz").display()
        )),
        "{error}"
    );
}
