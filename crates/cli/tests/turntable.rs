//! `glint render --turntable N`: N views round the scene as an animated GIF, an
//! animated WebP, an MP4 (through ffmpeg) or a directory of PNG frames, frame 0 the
//! still; `--camera-path KEYS --frames N`: N views along camera keys; bad requests
//! fail with one line and leave nothing behind (issue 43 item 4).

mod common;

use std::path::Path;
use std::process::Command;

use common::{fails, ok};

/// A small asymmetric scene (the Shepp-Logan head: its ellipses are not symmetric
/// about the vertical axis, so views round it differ).
const SCENE: [&str; 6] = [
    "--phantom",
    "shepp-logan",
    "--phantom-size",
    "32",
    "--size",
    "40x32",
];

/// `glint render -q SCENE EXTRA -o OUT`.
fn render(out: &Path, extra: &[&str]) -> String {
    let mut args = vec!["render", "-q"];
    args.extend(SCENE);
    args.extend(extra);
    args.extend(["-o", out.to_str().unwrap()]);
    ok(&args)
}

/// The files in `dir`, sorted by name.
fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A decoded GIF frame: width, height, delay (hundredths of a second), RGBA pixels.
type GifFrame = (u16, u16, u16, Vec<u8>);

/// A GIF's frames as RGBA buffers, with the logical screen's size.
fn gif_frames(path: &Path) -> ((u16, u16), Vec<GifFrame>) {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(std::fs::File::open(path).unwrap())
        .unwrap();
    let screen = (decoder.width(), decoder.height());
    let mut frames = Vec::new();
    while let Some(f) = decoder.read_next_frame().unwrap() {
        frames.push((f.width, f.height, f.delay, f.buffer.to_vec()));
    }
    (screen, frames)
}

#[test]
fn a_gif_turntable_has_n_frames_of_the_size_asked_that_differ() {
    let dir = tempfile::tempdir().unwrap();
    let gif = dir.path().join("spin.gif");
    render(&gif, &["--turntable", "4", "--fps", "25"]);
    let (screen, frames) = gif_frames(&gif);
    assert_eq!(screen, (40, 32));
    assert_eq!(frames.len(), 4);
    for (w, h, delay, _) in &frames {
        assert_eq!((*w, *h, *delay), (40, 32, 4), "a 40x32 frame every 1/25 s");
    }
    // A quarter turn shows another side of the head; half a turn mirrors it.
    for k in 1..4 {
        assert_ne!(frames[0].3, frames[k].3, "frame {k} equals frame 0");
    }
    // Only the GIF: the temporary file was renamed.
    assert_eq!(files(dir.path()), ["spin.gif"]);
}

#[test]
fn a_directory_turntable_writes_png_frames_and_frame_0_is_the_still() {
    let dir = tempfile::tempdir().unwrap();
    let still = dir.path().join("still.png");
    render(&still, &[]);
    // A path ending in '/' is a directory to create.
    let frames = dir.path().join("frames");
    let out = format!("{}/", frames.display());
    render(Path::new(&out), &["--turntable", "4"]);
    assert_eq!(
        files(&frames),
        [
            "frame-0000.png",
            "frame-0001.png",
            "frame-0002.png",
            "frame-0003.png"
        ]
    );
    let read = |name: &str| std::fs::read(frames.join(name)).unwrap();
    assert_eq!(read("frame-0000.png"), std::fs::read(&still).unwrap());
    for k in 1..4 {
        assert_ne!(read(&format!("frame-{k:04}.png")), read("frame-0000.png"));
    }
    // Frame 1 of 4 is the still turned by 90 degrees of azimuth.
    let turned = dir.path().join("turned.png");
    render(&turned, &["--azimuth", "90"]);
    assert_eq!(read("frame-0001.png"), std::fs::read(&turned).unwrap());
    // An existing directory (no slash) takes the frames too, at 16 bits.
    let again = dir.path().join("again");
    std::fs::create_dir(&again).unwrap();
    render(&again, &["--turntable", "2", "--depth", "16"]);
    assert_eq!(files(&again), ["frame-0000.png", "frame-0001.png"]);
    assert_eq!(std::fs::read(again.join("frame-0000.png")).unwrap()[24], 16);
}

/// A decoded WebP frame: its duration (ms) and RGB pixels.
type WebPFrame = (u32, Vec<u8>);

/// An animated WebP's frames, with its canvas's size, decoded by image-webp's decoder.
fn webp_frames(path: &Path) -> ((u32, u32), Vec<WebPFrame>) {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut decoder = image_webp::WebPDecoder::new(file).unwrap();
    assert!(decoder.is_animated());
    let size = decoder.dimensions();
    let mut buf = vec![0u8; decoder.output_buffer_size().unwrap()];
    let channels = buf.len() / (size.0 * size.1) as usize;
    let frames = (0..decoder.num_frames())
        .map(|_| {
            let ms = decoder.read_frame(&mut buf).unwrap();
            (
                ms,
                buf.chunks(channels).flat_map(|p| p[..3].to_vec()).collect(),
            )
        })
        .collect();
    (size, frames)
}

/// A PNG's 8-bit RGB pixels.
fn png_rgb(path: &Path) -> Vec<u8> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0u8; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.line_size / info.width as usize;
    buf[..info.buffer_size()]
        .chunks(channels)
        .flat_map(|p| p[..3].to_vec())
        .collect()
}

#[test]
fn a_webp_turntable_holds_the_png_frames_losslessly() {
    let dir = tempfile::tempdir().unwrap();
    let webp = dir.path().join("spin.webp");
    render(&webp, &["--turntable", "3", "--fps", "20"]);
    let out = format!("{}/", dir.path().join("frames").display());
    render(Path::new(&out), &["--turntable", "3"]);
    let (size, frames) = webp_frames(&webp);
    assert_eq!(size, (40, 32));
    assert_eq!(frames.len(), 3);
    for (k, (ms, rgb)) in frames.iter().enumerate() {
        assert_eq!(*ms, 50, "a frame every 1/20 s");
        let png = png_rgb(&dir.path().join(format!("frames/frame-{k:04}.png")));
        assert!(rgb == &png, "WebP frame {k} differs from the PNG frame");
    }
    assert_eq!(files(dir.path()), ["frames", "spin.webp"]);
}

#[test]
fn camera_path_frames_are_the_stills_at_the_interpolated_cameras() {
    let dir = tempfile::tempdir().unwrap();
    let keys = dir.path().join("keys.json");
    std::fs::write(
        &keys,
        r#"[{"azimuth": 0, "elevation": 0, "zoom": 1},
            {"azimuth": 90, "elevation": 40, "zoom": 4}]"#,
    )
    .unwrap();
    let out = format!("{}/", dir.path().join("path").display());
    render(
        Path::new(&out),
        &["--camera-path", keys.to_str().unwrap(), "--frames", "3"],
    );
    // Frame 1 of 3 is half way: azimuth and elevation linear, zoom geometric.
    for (k, camera) in [
        (0, ["0", "0", "1"]),
        (1, ["45", "20", "2"]),
        (2, ["90", "40", "4"]),
    ] {
        let still = dir.path().join(format!("still-{k}.png"));
        let [az, el, zoom] = camera;
        render(
            &still,
            &["--azimuth", az, "--elevation", el, "--zoom", zoom],
        );
        let frame = dir.path().join(format!("path/frame-{k:04}.png"));
        assert!(
            std::fs::read(&frame).unwrap() == std::fs::read(&still).unwrap(),
            "frame {k} is not the still at {camera:?}"
        );
    }
}

/// `ffprobe`'s width, height and counted frames of a video's first stream.
fn probe(path: &Path) -> String {
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-select_streams", "v:0", "-count_frames"])
        .args(["-show_entries", "stream=width,height,nb_read_frames"])
        .args(["-of", "csv=p=0"])
        .arg(path)
        .output()
        .expect("run ffprobe");
    assert!(out.status.success(), "{:?}", out);
    String::from_utf8(out.stdout).unwrap().trim().to_string()
}

#[test]
fn an_mp4_turntable_goes_through_ffmpeg() {
    let on_path = |tool: &str| {
        Command::new(tool)
            .arg("-version")
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if !(on_path("ffmpeg") && on_path("ffprobe")) {
        // Strict mode (CI, scripts/test): a failure naming the tool.
        glint_testkit::missing("ffmpeg and ffprobe (scripts/install-deps)");
        return;
    }
    glint_testkit::ran("ffmpeg (glint render --turntable -o x.mp4)");
    let dir = tempfile::tempdir().unwrap();
    let mp4 = dir.path().join("spin.mp4");
    render(&mp4, &["--turntable", "6", "--fps", "30"]);
    assert_eq!(probe(&mp4), "40,32,6");
    assert_eq!(files(dir.path()), ["spin.mp4"]);
    // An odd size is padded to even sides (yuv420p).
    let odd = dir.path().join("odd.mp4");
    let mut args = vec!["render", "-q"];
    args.extend(&SCENE[..4]);
    args.extend(["--size", "33x21", "--turntable", "3", "-o"]);
    args.push(odd.to_str().unwrap());
    ok(&args);
    assert_eq!(probe(&odd), "34,22,3");
}

#[test]
fn an_mp4_without_ffmpeg_fails_in_one_line_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let empty = tempfile::tempdir().unwrap();
    let mp4 = dir.path().join("spin.mp4");
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["render", "-q", "--turntable", "4", "-o"])
        .arg(&mp4)
        .env("PATH", empty.path())
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("ffmpeg is not on PATH"), "{err}");
    assert!(files(dir.path()).is_empty(), "left {:?}", files(dir.path()));
}

#[test]
fn bad_turntables_fail_in_one_line_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    // D/ stands for the test's directory.
    let cases = [
        ("--turntable 1 -o D/a.gif", "2..=3600"),
        ("--turntable 0 -o D/a.gif", "2..=3600"),
        ("--turntable 3601 -o D/a.gif", "2..=3600"),
        ("--turntable x -o D/a.gif", "--turntable"),
        (
            "--turntable 4 -o D/a.xyz",
            "a.xyz: expected an animated GIF",
        ),
        (
            "--turntable 4 -o D/a.png",
            "a.png: expected an animated GIF",
        ),
        ("--turntable 4 -o D/a", "expected an animated GIF"),
        ("--turntable 4 --fps 0 -o D/a.gif", "1..=120"),
        ("--turntable 4 --fps 500 -o D/a.gif", "1..=120"),
        (
            "--fps 30 -o D/a.png",
            "--fps is the frame rate of a --turntable",
        ),
        ("--frames 4 -o D/a.gif", "--camera-path"),
        (
            "--camera-path K/two.json --frames 4 --turntable 4 -o D/a.gif",
            "--turntable",
        ),
        ("--camera-path K/two.json -o D/a.gif", "--frames"),
        ("--camera-path K/two.json --frames 1 -o D/a.gif", "2..=3600"),
        (
            "--camera-path K/two.json --frames 4 -o D/a.xyz",
            "expected an animated GIF",
        ),
        (
            "--camera-path K/missing.json --frames 4 -o D/a.gif",
            "[1]: missing field `zoom`",
        ),
        (
            "--camera-path K/one.json --frames 4 -o D/a.gif",
            "1 keys: expected 2..=",
        ),
        (
            "--camera-path K/unknown.json --frames 4 -o D/a.gif",
            "unknown field `target`",
        ),
        (
            "--camera-path K/none.json --frames 4 -o D/a.gif",
            "cannot read the camera keys",
        ),
        ("--turntable 4 --repeat 3 -o D/a.gif", "--repeat"),
        ("--turntable 4 -o D/missing/a.gif", "does not exist"),
        ("--turntable 4 -o D/missing/frames/", "does not exist"),
        ("--turntable 4 --step 0 -o D/frames/", "step"),
        ("--turntable 4 --step 0 -o D/a.gif", "step"),
        (
            "--turntable 4 --preset nonsense -o D/frames/",
            "unknown preset",
        ),
    ];
    // K/ stands for a directory of camera key files.
    let keys = tempfile::tempdir().unwrap();
    let key = r#"{"azimuth": 0, "elevation": 0, "zoom": 1}"#;
    for (name, text) in [
        ("two.json", format!("[{key}, {key}]")),
        (
            "missing.json",
            format!(r#"[{key}, {{"azimuth": 0, "elevation": 0}}]"#),
        ),
        ("one.json", format!("[{key}]")),
        (
            "unknown.json",
            format!(r#"[{key}, {{"azimuth": 0, "elevation": 0, "zoom": 1, "target": [0, 0, 0]}}]"#),
        ),
    ] {
        std::fs::write(keys.path().join(name), text).unwrap();
    }
    let root = format!("{}/", dir.path().display());
    let key_root = format!("{}/", keys.path().display());
    for (case, needle) in cases {
        let case = case.replace("D/", &root).replace("K/", &key_root);
        let mut args = vec!["render", "-q", "--phantom-size", "16", "--size", "16x16"];
        args.extend(case.split_whitespace());
        let err = fails(&args);
        assert!(err.contains(needle), "{case}: '{err}' lacks '{needle}'");
        assert!(
            files(dir.path()).is_empty(),
            "{case} left {:?}",
            files(dir.path())
        );
    }
}
