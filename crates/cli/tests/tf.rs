//! Transfer functions by hand (issue 43 item 3): `glint tf export` to 3D Slicer's
//! `.vp` and ParaView's colour map JSON, `--tf FILE.vp|FILE.json` read back, and
//! `--window W --window-level L`; bad files and values fail with one line and leave
//! no output.

mod common;

use std::path::Path;

use common::{fails, ok};

/// `glint render -q` of a small phantom with `extra`, to `out`; the PNG's bytes.
fn render(out: &Path, extra: &[&str]) -> Vec<u8> {
    let mut args = vec![
        "render",
        "-q",
        "--phantom",
        "shepp-logan",
        "--phantom-size",
        "32",
        "--size",
        "40x32",
    ];
    args.extend(extra);
    args.extend(["-o", out.to_str().unwrap()]);
    ok(&args);
    std::fs::read(out).unwrap()
}

#[test]
fn a_preset_exported_to_slicer_and_paraview_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let vp = dir.path().join("bone.vp");
    ok(&[
        "tf",
        "export",
        "--preset",
        "ct-bone",
        "-o",
        vp.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&vp).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    // Slicer's presets.xml numbers for CT-Bone, in the storage node's line order:
    // interpolation, shade, diffuse, ambient, specular, power, opacity, gradient, colour.
    assert_eq!(&lines[..6], ["1", "1", "0.9", "0.1", "0.2", "10"], "{text}");
    assert_eq!(
        lines[6],
        "8 -3024 0 -16.4458 0 641.385 0.715686 3071 0.705882"
    );
    assert_eq!(lines[7], "4 0 1 255 1");
    assert!(lines[8].starts_with("16 -3024 0 0 0 -16.4458 0.729412 0.254902 0.301961"));
    let json = dir.path().join("bone.json");
    ok(&[
        "tf",
        "export",
        "--preset",
        "ct-bone",
        "-o",
        json.to_str().unwrap(),
    ]);
    let map: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(map[0]["Name"], "ct-bone");
    assert_eq!(map[0]["RGBPoints"][4], -16.4458);
    assert_eq!(map[0]["Points"].as_array().unwrap().len(), 16);
    // The .vp carries the material: rendering it is rendering the preset.
    let preset = render(&dir.path().join("preset.png"), &["--preset", "ct-bone"]);
    let from_vp = render(&dir.path().join("vp.png"), &["--tf", vp.to_str().unwrap()]);
    assert_eq!(preset, from_vp);
    let from_alias = render(
        &dir.path().join("alias.png"),
        &["--transfer-function", vp.to_str().unwrap()],
    );
    assert_eq!(preset, from_alias);
    // Converted: Slicer to ParaView keeps the function.
    let conv = dir.path().join("conv.json");
    ok(&[
        "tf",
        "export",
        "--from",
        vp.to_str().unwrap(),
        "-o",
        conv.to_str().unwrap(),
    ]);
    let conv: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&conv).unwrap()).unwrap();
    assert_eq!(conv[0]["Name"], "bone");
    assert_eq!(conv[0]["RGBPoints"], map[0]["RGBPoints"]);
}

#[test]
fn window_and_level_equal_the_hand_remapped_function() {
    let dir = tempfile::tempdir().unwrap();
    // A ParaView map written by hand: a ramp over 0..1, and the same ramp moved by
    // hand to the window 0.5 wide at level 0.5 (0.25..0.75).
    let write = |name: &str, lo: f64, hi: f64| {
        let path = dir.path().join(name);
        let text = format!(
            r#"[{{"Name": "ramp", "ColorSpace": "RGB", "RGBPoints": [{lo}, 1, 0.5, 0.2, {hi}, 1, 1, 1],
               "Points": [{lo}, 0, 0.5, 0, {hi}, 0.2, 0.5, 0]}}]"#
        );
        std::fs::write(&path, text).unwrap();
        path
    };
    let ramp = write("ramp.json", 0.0, 1.0);
    let moved = write("moved.json", 0.25, 0.75);
    let windowed = render(
        &dir.path().join("w.png"),
        &[
            "--tf",
            ramp.to_str().unwrap(),
            "--window",
            "0.5",
            "--window-level",
            "0.5",
        ],
    );
    let by_hand = render(
        &dir.path().join("h.png"),
        &["--tf", moved.to_str().unwrap()],
    );
    let plain = render(&dir.path().join("p.png"), &["--tf", ramp.to_str().unwrap()]);
    assert_eq!(windowed, by_hand);
    assert_ne!(windowed, plain);
}

#[test]
fn bad_files_and_windows_fail_with_one_line_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.png");
    let o = out.to_str().unwrap();
    let short = dir.path().join("short.vp");
    std::fs::write(
        &short,
        "1\n1\n0.9\n0.1\n0.2\n10\n6 0 0 1 1\n4 0 1 255 1\n4 0 1 1 1\n",
    )
    .unwrap();
    let word = dir.path().join("word.vp");
    std::fs::write(
        &word,
        "1\n1\nshiny\n0.1\n0.2\n10\n4 0 0 1 1\n4 0 1 255 1\n4 0 1 1 1\n",
    )
    .unwrap();
    let pv = dir.path().join("pv.json");
    std::fs::write(&pv, r#"[{"Name": "x", "RGBPoints": [0, 1, 1]}]"#).unwrap();
    let txt = dir.path().join("tf.txt");
    std::fs::write(&txt, "1").unwrap();
    let (s, w, p, t) = (
        short.to_str().unwrap(),
        word.to_str().unwrap(),
        pv.to_str().unwrap(),
        txt.to_str().unwrap(),
    );
    for (args, needle) in [
        (
            vec!["render", "--tf", s, "-o", o],
            "count 6 but 4 values follow",
        ),
        (vec!["render", "--tf", w, "-o", o], "line 3 (diffuse)"),
        (vec!["render", "--tf", p, "-o", o], "multiple of 4"),
        (vec!["render", "--tf", t, "-o", o], "unknown extension"),
        (
            vec!["render", "--window", "0", "--window-level", "1", "-o", o],
            "window 0",
        ),
        (
            vec!["render", "--window", "10", "-o", o],
            "required arguments",
        ),
    ] {
        let err = fails(&args);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} left an output");
    }
    let bad_out = dir.path().join("x.txt");
    let err = fails(&[
        "tf",
        "export",
        "--preset",
        "ct-bone",
        "-o",
        bad_out.to_str().unwrap(),
    ]);
    assert!(err.contains(".vp"), "{err}");
    let err = fails(&["tf", "export", "--preset", "ct-nonsense", "-o", s]);
    assert!(err.contains("unknown preset"), "{err}");
    assert!(!bad_out.exists());
    // A refused export leaves the file it would have replaced as it was.
    let err = fails(&["tf", "export", "--from", w, "-o", s]);
    assert!(err.contains("line 3"), "{err}");
    assert!(std::fs::read_to_string(&short)
        .unwrap()
        .starts_with("1\n1\n0.9"));
}
