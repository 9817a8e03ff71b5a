//! The report in a real browser: a BIDS study of three good volumes and a corrupt one
//! is run, then Debian's headless Chromium, driven by playwright-core
//! (crates/batch/tests/report.mjs, with the playwright-core that crates/view/browser
//! installs), opens `index.html` from the disk: every thumbnail must decode, the
//! failed input must show as one card with its error line, sorting by subject must
//! order the labels as numbers, "failed only" must hide the others, and nothing may be
//! fetched from anywhere but the disk. Needs `node`, `chromium`
//! (scripts/install-deps) and `npm ci` in crates/view/browser (scripts/test); in
//! strict mode (`GLINT_STRICT` or `CI` set; glint_testkit) a missing piece fails the
//! test.

use std::path::Path;
use std::process::Command;

use glint_batch::{discover, finish, run_local, Discover, LocalOptions, Spec};
use glint_io::{nifti, Endian};
use glint_render::{Phantom, Scene, View};

#[test]
fn the_report_opens_from_the_disk_with_its_thumbnails_and_the_error() {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    if !glint_testkit::browser_tools(&manifest.join("../view/browser")) {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let bids = dir.path().join("bids");
    std::fs::create_dir(&bids).unwrap();
    std::fs::write(bids.join("dataset_description.json"), b"{}").unwrap();
    for (sub, size) in [("10", 24), ("2", 26), ("1", 28)] {
        let anat = bids.join(format!("sub-{sub}/anat"));
        std::fs::create_dir_all(&anat).unwrap();
        let vol = Phantom::Head.volume(size).unwrap();
        let path = anat.join(format!("sub-{sub}_T1w.nii.gz"));
        nifti::write(&path, &vol, true, Endian::Little).unwrap();
    }
    let anat = bids.join("sub-3/anat");
    std::fs::create_dir_all(&anat).unwrap();
    std::fs::write(anat.join("sub-3_T1w.nii.gz"), b"\x1f\x8b corrupt").unwrap();

    let out = dir.path().join("qc");
    let items = discover(&[bids], &Discover::default()).unwrap();
    let scene = Scene {
        size: [48, 40],
        ..Scene::default()
    };
    let spec = Spec::new(scene, vec![View::Left, View::Superior], true);
    let outcomes = run_local(&items, &spec, &out, &LocalOptions::default(), &|_| {}).unwrap();
    let rows: Vec<_> = outcomes.into_iter().map(|o| o.row).collect();
    let summary = finish(&out, &rows).unwrap();
    assert_eq!((summary.ok, summary.failed), (3, 1));

    let shot = Path::new(env!("CARGO_TARGET_TMPDIR")).join("glint-batch-report.png");
    let run = Command::new("node")
        .arg(manifest.join("tests/report.mjs"))
        .arg(out.join("index.html"))
        .arg(&shot)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "report.mjs failed: {stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let page: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    // Three inputs, a mosaic and slices each, all decoded by the browser.
    assert_eq!(page["thumbnails"], 6, "{page}");
    assert_eq!(page["decoded"], 6, "{page}");
    let failed = page["failed"].as_array().unwrap();
    assert_eq!(failed.len(), 1, "{page}");
    assert_eq!(failed[0]["id"], "sub-3_T1w");
    let error = failed[0]["error"].as_str().unwrap();
    assert!(error.contains("sub-3_T1w.nii.gz"), "{error}");
    let want = rows.iter().find(|r| r.id == "sub-3_T1w").unwrap();
    assert_eq!(Some(error), want.error.as_deref());
    assert_eq!(
        page["bySubject"],
        serde_json::json!(["sub-1_T1w", "sub-2_T1w", "sub-3_T1w", "sub-10_T1w"])
    );
    assert_eq!(page["visibleWhenOnlyFailed"], 1, "{page}");
    assert_eq!(page["remote"], serde_json::json!([]), "{page}");
    assert_eq!(page["errors"], serde_json::json!([]), "{page}");
    eprintln!(
        "report in the browser: {page}; screenshot {}",
        shot.display()
    );
    glint_testkit::ran("chromium + node (batch report browser test)");
}
