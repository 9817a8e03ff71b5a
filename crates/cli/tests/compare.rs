//! `glint compare` end to end on a small phantom: the metrics of exact against itself
//! are those of equal images, a cheaper lobe shows a difference that shrinks as v
//! grows (K_v converges to cos^n), the picture and the sweep files are written, and bad
//! input gives one line and no file.

mod common;

use std::path::Path;

/// `glint compare ARGS`.
fn glint(args: &[&str]) -> std::process::Output {
    common::glint(&[&["compare"], args].concat())
}

/// `glint compare ARGS`, which must succeed; its stdout.
fn ok(args: &[&str]) -> String {
    common::ok(&[&["compare"], args].concat())
}

/// A small, quick scene: the phantom on a 32^3 grid, 48x40 pixels.
const SMALL: [&str; 4] = ["--phantom-size", "32", "--size", "48x40"];

/// Width and height from a PNG's IHDR.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

fn json_compare(dir: &Path, extra: &[&str]) -> serde_json::Value {
    let out = dir.join("cmp.png");
    let mut args = vec!["-q", "--json", "-o", out.to_str().unwrap()];
    args.extend_from_slice(&SMALL);
    args.extend_from_slice(extra);
    serde_json::from_str(&ok(&args)).expect("JSON on stdout")
}

#[test]
fn exact_against_itself_is_a_perfect_match() {
    let dir = tempfile::tempdir().unwrap();
    let doc = json_compare(dir.path(), &["--lobe", "exact", "--n", "100"]);
    let c = &doc["comparisons"][0];
    assert_eq!(c["lobe"], "exact");
    let m = &c["image"];
    assert_eq!(m["pixels"], 48 * 40);
    assert!(
        m["psnr_db"].is_null(),
        "equal images have infinite PSNR: {m}"
    );
    assert_eq!(m["ssim"], 1.0);
    assert_eq!(m["delta_e"]["max"], 0.0);
    assert_eq!(m["flip_mean"], 0.0);
    assert_eq!(doc["scene"]["lobe"]["n"], 100.0);
}

#[test]
fn the_lobe_differs_from_exact_less_as_v_grows() {
    let dir = tempfile::tempdir().unwrap();
    let mean_de = |v: &str| {
        let doc = json_compare(dir.path(), &["--lobe", "k", "--n", "200", "--v", v]);
        let c = &doc["comparisons"][0];
        assert_eq!(c["v"], v.parse::<u64>().unwrap());
        // The render's time is reported (its value is wall time: not asserted on).
        assert!(c["render_ms"].as_f64().is_some_and(f64::is_finite), "{c}");
        // The highlight exists on the phantom and is part of the image.
        let hl = doc["highlight"]["pixels"].as_u64().unwrap();
        assert!(hl > 0 && hl < 48 * 40, "highlight pixels {hl}");
        assert_eq!(c["highlight"]["pixels"], hl);
        c["image"]["delta_e"]["mean"].as_f64().unwrap()
    };
    let (coarse, fine) = (mean_de("2"), mean_de("6"));
    assert!(coarse > 0.0, "K_2 at n = 200 must differ from cos^n");
    assert!(
        fine < coarse,
        "K_6 {fine} should be closer to exact than K_2 {coarse}"
    );
}

#[test]
fn several_lobes_give_one_table_and_a_row_each_in_the_picture() {
    let dir = tempfile::tempdir().unwrap();
    let one = dir.path().join("one.png");
    let three = dir.path().join("three.png");
    let mut args = vec!["-q", "--lobe", "k", "-o", one.to_str().unwrap()];
    args.extend_from_slice(&SMALL);
    let text = ok(&args);
    assert!(
        text.contains("highlight") && text.contains("PSNR"),
        "{text}"
    );
    let mut args = vec!["-q", "--lobe", "k", "--lobe", "g", "--lobe", "schlick"];
    args.extend(["-o", three.to_str().unwrap()]);
    args.extend_from_slice(&SMALL);
    let text = ok(&args);
    for lobe in ["k ", "g ", "schlick "] {
        let rows = text.lines().filter(|l| l.starts_with(lobe)).count();
        assert_eq!(rows, 2, "{lobe}: image and highlight rows in\n{text}");
    }
    let (w1, h1) = png_size(&one);
    let (w3, h3) = png_size(&three);
    // Three panels of 48 pixels side by side; three rows stack three 40-pixel images.
    assert!(w1 >= 3 * 48 && w1 == w3);
    assert!(h3 > h1 && h3 >= 3 * 40, "{h1} -> {h3}");
}

#[test]
fn sweep_writes_the_table_and_the_plots() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep");
    let mut args = vec!["-q", "--sweep", "--sweep-n", "20,200", "--sweep-v", "2,4"];
    args.extend([
        "--lobe",
        "k",
        "--lobe",
        "schlick",
        "-o",
        out.to_str().unwrap(),
    ]);
    args.extend_from_slice(&SMALL);
    let md = ok(&args);
    assert!(md.contains("| lobe | n | v |"), "{md}");
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "sweep-delta-e-highlight.png",
            "sweep-delta-e-highlight.svg",
            "sweep-delta-e.png",
            "sweep-delta-e.svg",
            "sweep.csv",
            "sweep.md"
        ]
    );
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    // Per n: k at two v and schlick once (no v), each as image and highlight rows.
    assert_eq!(csv.lines().count(), 1 + 2 * 2 * (2 + 1), "{csv}");
    assert!(
        csv.lines().any(|l| l.starts_with("image,schlick,200,-,")),
        "{csv}"
    );
}

#[test]
fn bad_input_fails_with_one_line_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cmp.png");
    let o = out.to_str().unwrap();
    let cases: [(&[&str], &str); 10] = [
        (&["--sweep", "--sweep-n", "0,10", "-o", o], "n > 0"),
        (&["/nonexistent/volume.nii.gz", "-o", o], "volume"),
        (&["--n", "-5", "-o", o], "n = -5"),
        (&["--v", "40", "-o", o], "v = 40"),
        (&["--lobe", "cosine", "-o", o], "cosine"),
        (&["-o", "/nonexistent/dir/cmp.png"], "does not exist"),
        (
            &["--sweep", "--sweep-n", "10,nan", "-o", o],
            "invalid n = NaN",
        ),
        (&["--size", "4x4", "-o", o], "SSIM window"),
        (&["--reference-spp", "64", "-o", o], "need --lighting path"),
        (
            &[
                "--lighting",
                "path",
                "--spp",
                "8",
                "--reference-spp",
                "4",
                "-o",
                o,
            ],
            "must exceed --spp 8",
        ),
    ];
    for (args, needle) in cases {
        let mut all = args.to_vec();
        all.push("-q");
        let r = glint(&all);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{args:?} should fail");
        assert!(err.contains(needle), "{args:?}: '{err}' lacks '{needle}'");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            0,
            "{args:?} left a file"
        );
    }
}

#[test]
fn the_hardware_unit_is_compared_like_any_lobe() {
    let dir = tempfile::tempdir().unwrap();
    let unit = dir.path().join("unit.json");
    std::fs::write(&unit, r#"{"out_bits": 12}"#).unwrap();
    let doc = json_compare(
        dir.path(),
        &[
            "--lobe",
            "hw",
            "--lobe",
            "k",
            "--hw-config",
            unit.to_str().unwrap(),
            "--n",
            "40",
        ],
    );
    let rows = doc["comparisons"].as_array().unwrap();
    assert_eq!(rows.len(), 2, "{doc}");
    assert_eq!(
        (&rows[0]["lobe"], &rows[1]["lobe"]),
        (&"hw".into(), &"k".into())
    );
    assert_eq!(rows[0]["v"], 4, "the unit's v");
    for row in rows {
        // n = 40 is far from cos^n's shape at v = 4: both differ from exact.
        assert!(
            row["image"]["delta_e"]["max"].as_f64().unwrap() > 0.0,
            "{row}"
        );
    }
    // The sweep varies v, which a unit fixes.
    let out = glint(&[
        "-q",
        "--sweep",
        "--lobe",
        "hw",
        "-o",
        dir.path().join("s").to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("hw"));
}
