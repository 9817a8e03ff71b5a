//! `glint render` and `glint compare` on meshes, end to end: the fsaverage5
//! hemispheres with a sulcal-depth overlay, a dumped mesh scene that renders again bit
//! for bit, compare on a mesh, an isosurface of a volume, and bad overlays refused with
//! one line and no file.

mod common;

use common::{glint, ok};
use std::path::{Path, PathBuf};

/// `glint ARGS -q -o OUT --dump-scene SCENE`, which must succeed; the dumped scene.
fn render_dumped(args: &[&str], out: &Path, scene: &Path) -> serde_json::Value {
    let mut argv = args.to_vec();
    argv.extend(["-q", "-o", out.to_str().unwrap()]);
    argv.extend(["--dump-scene", scene.to_str().unwrap()]);
    ok(&argv);
    serde_json::from_str(&std::fs::read_to_string(scene).unwrap()).unwrap()
}

/// A sample file, or `None` (with a note) when it is missing outside strict mode; in
/// strict mode (glint_testkit) a missing sample fails the test.
fn sample(name: &str) -> Option<PathBuf> {
    glint_testkit::sample(name)
}

/// An 8-bit RGB(A) PNG decoded: width, height, channels, samples.
fn decode(path: &Path) -> (u32, u32, usize, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    let channels = info.color_type.samples();
    (info.width, info.height, channels, buf)
}

/// A closed octahedron (6 vertices, 8 triangles, outward winding) as OBJ text.
const OCTAHEDRON: &str = "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n\
f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";

/// A PLY holding `n` vertices with a scalar property (values 0, 1, ..., n-1) and one
/// triangle, as a per-vertex overlay file.
fn ply_scalars(n: usize) -> String {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n\
property float z\nproperty float scalar\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    );
    for i in 0..n {
        s.push_str(&format!("{i} {} 0 {i}\n", i % 2));
    }
    s.push_str("3 0 1 2\n");
    s
}

/// Writes the octahedron and a matching 6-value overlay into `dir`.
fn octahedron(dir: &Path) -> (String, String) {
    let mesh = dir.join("octa.obj");
    std::fs::write(&mesh, OCTAHEDRON).unwrap();
    let overlay = dir.join("octa-values.ply");
    std::fs::write(&overlay, ply_scalars(6)).unwrap();
    (
        mesh.to_str().unwrap().to_string(),
        overlay.to_str().unwrap().to_string(),
    )
}

/// Issue 16's done-when: both fsaverage5 pial hemispheres in one scene, the left one
/// with its sulcal depth through a colour map, with per-pixel highlights and a colour
/// bar.
#[test]
fn fsaverage5_hemispheres_with_a_sulcal_depth_overlay() {
    let (Some(lh), Some(rh), Some(sulc)) = (
        sample("fsaverage5_pial_left.gii.gz"),
        sample("fsaverage5_pial_right.gii.gz"),
        sample("fsaverage5_sulc_left.gii.gz"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let render = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let scene = dir.path().join(format!("{name}.json"));
        let mut args = vec![
            "render",
            lh.to_str().unwrap(),
            rh.to_str().unwrap(),
            "--overlay",
            sulc.to_str().unwrap(),
            "--view",
            "superior",
            "--size",
            "160x160",
        ];
        args.extend_from_slice(extra);
        let json = render_dumped(&args, &out, &scene);
        (decode(&out), json)
    };
    let ((w, h, ch, lit), scene) = render("lit.png", &[]);
    assert_eq!((w, h), (160, 160));
    // The resolved scene: no volume, two meshes, the overlay's range inside the
    // sulcal depth's (-1.4937 .. 1.8069, nibabel 5.4.2 via scripts/fixtures/gifti-reference.py)
    // and spanning zero (sulci and gyri).
    assert_eq!(scene["input"], "none");
    assert_eq!(scene["mode"], "surface");
    assert_eq!(scene["meshes"].as_array().unwrap().len(), 2);
    let overlay = &scene["meshes"][0]["overlay"];
    assert_eq!(overlay["colormap"], "viridis");
    let (lo, hi) = (
        overlay["range"][0].as_f64().unwrap(),
        overlay["range"][1].as_f64().unwrap(),
    );
    assert!(
        (-1.4938..0.0).contains(&lo) && hi > 0.0 && hi <= 1.807,
        "{lo} {hi}"
    );
    assert!(scene["meshes"][1].get("overlay").is_none());
    // Seen from above, both hemispheres cover the image's left and right halves.
    let covered = |x0: u32, x1: u32| {
        (0..h)
            .flat_map(|y| (x0..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let k = (y * w + x) as usize * ch;
                lit[k..k + 3].iter().any(|&c| c > 0)
            })
            .count()
    };
    assert!(covered(10, 70) > 1500 && covered(80, 130) > 1500);
    // Highlights: the same scene without the specular term is darker where the lobe
    // adds light, by far more than rounding.
    let ((_, _, _, matte), _) = render("matte.png", &["--specular", "0"]);
    let gain = lit
        .iter()
        .zip(&matte)
        .map(|(&a, &b)| i32::from(a) - i32::from(b))
        .max()
        .unwrap();
    assert!(gain > 40, "the brightest highlight adds {gain}/255");
    // The colour bar at the right edge: viridis' yellow top above its purple bottom.
    let px = |x: u32, y: u32| {
        let k = (y * w + x) as usize * ch;
        [lit[k], lit[k + 1], lit[k + 2]]
    };
    let x = w - w / 40 - 3;
    let (top, bottom) = (px(x, h / 5 + 3), px(x, h * 4 / 5 - 3));
    assert!(top[0] > 200 && top[1] > 200 && top[2] < 100, "{top:?}");
    assert!(bottom[0] < 100 && bottom[2] > 60, "{bottom:?}");
}

#[test]
fn a_dumped_mesh_scene_renders_again_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, overlay) = octahedron(dir.path());
    let d = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let scene = render_dumped(
        &[
            "render",
            &mesh,
            "--overlay",
            &overlay,
            "--colormap",
            "rdbu",
            "--ssaa",
            "4",
            "--size",
            "96x80",
            "--azimuth",
            "25",
            "--elevation",
            "20",
            "--lobe",
            "exact",
        ],
        d("a.png").as_ref(),
        d("a.json").as_ref(),
    );
    assert_eq!(scene["ssaa"], 4);
    assert_eq!(scene["meshes"][0]["overlay"]["colormap"], "rdbu");
    assert_eq!(scene["meshes"][0]["overlay"]["array"], 0);
    // Values 0..5: the 2nd and 98th percentiles of six values (nearest rank, ranks
    // round(5 * 0.02) = 0 and round(5 * 0.98) = 5) are the ends; no sign change, so
    // the diverging map is not centred on zero.
    assert_eq!(
        scene["meshes"][0]["overlay"]["range"],
        serde_json::json!([0.0, 5.0])
    );
    ok(&["render", "--scene", &d("a.json"), "-q", "-o", &d("b.png")]);
    let (a, b) = (
        std::fs::read(d("a.png")).unwrap(),
        std::fs::read(d("b.png")).unwrap(),
    );
    assert!(a == b, "the dumped scene rendered a different image");
    // And a flag still overrides the file.
    ok(&[
        "render",
        "--scene",
        &d("a.json"),
        "--ssaa",
        "1",
        "-q",
        "-o",
        &d("c.png"),
    ]);
    assert_ne!(std::fs::read(d("c.png")).unwrap(), a);
}

#[test]
fn compare_works_on_a_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, _) = octahedron(dir.path());
    let out = dir.path().join("cmp.png");
    let text = ok(&[
        "compare",
        &mesh,
        "--size",
        "64x48",
        "--n",
        "200",
        "--lobe",
        "exact",
        "--lobe",
        "k",
        "--v",
        "2",
        "--json",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let c = &doc["comparisons"];
    assert_eq!(c[0]["lobe"], "exact");
    assert_eq!(c[0]["image"]["pixels"], 64 * 48);
    assert_eq!(c[0]["image"]["delta_e"]["max"], 0.0);
    // K_2 at n = 200 is far from cos^200 (the paper's table: v must grow with n), so
    // the highlight differs.
    assert_eq!(c[1]["lobe"], "k");
    assert!(
        c[1]["image"]["delta_e"]["max"].as_f64().unwrap() > 0.5,
        "{}",
        c[1]
    );
    // The figure: per lobe a row of three 64x48 panels (exact, the lobe, the ΔE map)
    // under a title, so at least 3 x 64 wide and 2 x 48 high, and not blank.
    let (w, h, channels, px) = decode(&out);
    assert!(w >= 3 * 64 && h >= 2 * 48, "{w}x{h}");
    let first = &px[..channels];
    let differ = px.chunks(channels).filter(|p| *p != first).count();
    assert!(
        differ * 10 > (w * h) as usize,
        "a nearly blank figure: {differ} pixels"
    );
}

/// A volume with a mesh in the default (composite) mode: the mesh, in front of the
/// volume, shows at the centre; the dump keeps both and the composite mode.
#[test]
fn a_ray_cast_volume_composites_over_a_mesh() {
    let dir = tempfile::tempdir().unwrap();
    // A 32^3 ball of 200 in 0, 1 mm voxels centred on the origin, as NRRD.
    let mut nrrd = b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 32 32 32\nspace: RAS\n\
space directions: (1,0,0) (0,1,0) (0,0,1)\nspace origin: (-15.5,-15.5,-15.5)\n\
encoding: raw\n\n"
        .to_vec();
    for z in 0..32 {
        for y in 0..32 {
            for x in 0..32 {
                let r2 = [x, y, z]
                    .map(|i| (i as f32 - 15.5).powi(2))
                    .iter()
                    .sum::<f32>();
                nrrd.push(if r2 < 144.0 { 200 } else { 0 });
            }
        }
    }
    let volume = dir.path().join("ball.nrrd");
    std::fs::write(&volume, nrrd).unwrap();
    // The octahedron scaled by 8 mm and moved 40 mm anterior, before the ball.
    let obj: String = OCTAHEDRON
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(v) => {
                let p: Vec<f32> = v.split(' ').map(|x| x.parse().unwrap()).collect();
                format!("v {} {} {}\n", 8.0 * p[0], 40.0 + 8.0 * p[1], 8.0 * p[2])
            }
            None => format!("{l}\n"),
        })
        .collect();
    let mesh = dir.path().join("front.obj");
    std::fs::write(&mesh, obj).unwrap();
    let (with, without) = (dir.path().join("with.png"), dir.path().join("without.png"));
    let scene = dir.path().join("s.json");
    let common = ["--view", "anterior", "--size", "48x48"];
    let vol = volume.to_str().unwrap();
    let s = render_dumped(
        &[&["render", vol, mesh.to_str().unwrap()], &common[..]].concat(),
        &with,
        &scene,
    );
    ok(&[
        &["render", vol],
        &common[..],
        &["-q", "-o", without.to_str().unwrap()],
    ]
    .concat());
    assert_eq!(s["mode"], "composite");
    assert_eq!(s["meshes"].as_array().map(Vec::len), Some(1), "{s}");
    let ((_, _, ch, a), (_, _, _, b)) = (decode(&with), decode(&without));
    let k = (24 * 48 + 24) * ch;
    assert_ne!(a[k..k + 3], b[k..k + 3], "the mesh shows at the centre");
    assert!(b[k..k + 3].iter().any(|&c| c > 20), "the ball shows alone");
    // The corners show the background alone, the same in both.
    assert_eq!(a[..3], b[..3]);
}

#[test]
fn a_volume_isosurface_renders_in_surface_mode() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("iso.png");
    let scene = dir.path().join("iso.json");
    let s = render_dumped(
        &[
            "render",
            "--phantom-size",
            "32",
            "--mode",
            "surface",
            "--size",
            "48x48",
        ],
        &out,
        &scene,
    );
    assert_eq!(s["mode"], "surface");
    assert!(
        s["iso"].is_number(),
        "the default iso value is written back: {s}"
    );
    let (_, _, ch, px) = decode(&out);
    let k = (24 * 48 + 24) * ch;
    assert!(
        px[k..k + 3].iter().any(|&c| c > 20),
        "the head covers the centre"
    );
}

/// A GIFTI shape file with two per-vertex arrays of `n` values: `i` and `n - 1 - i`.
fn gifti_two_arrays(n: usize) -> String {
    let data = |f: &dyn Fn(usize) -> usize| {
        let v: Vec<String> = (0..n).map(|i| f(i).to_string()).collect();
        format!(
            "<DataArray Intent=\"NIFTI_INTENT_SHAPE\" DataType=\"NIFTI_TYPE_FLOAT32\" \
ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"1\" Dim0=\"{n}\" Encoding=\"ASCII\" \
Endian=\"LittleEndian\" ExternalFileName=\"\" ExternalFileOffset=\"\"><Data>{}</Data></DataArray>\n",
            v.join(" ")
        )
    };
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<GIFTI Version=\"1.0\" NumberOfDataArrays=\"2\">\n{}{}</GIFTI>\n",
        data(&|i| i),
        data(&|i| n - 1 - i)
    )
}

/// `--overlay-array` picks a GIFTI file's array (written into the scene); the two
/// arrays of a file colour the mesh differently.
#[test]
fn overlay_array_chooses_the_files_array() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, _) = octahedron(dir.path());
    let two = dir.path().join("two.shape.gii");
    std::fs::write(&two, gifti_two_arrays(6)).unwrap();
    let render = |array: &str| {
        let out = dir.path().join(format!("a{array}.png"));
        let scene = dir.path().join(format!("a{array}.json"));
        let s = render_dumped(
            &[
                "render",
                &mesh,
                "--overlay",
                two.to_str().unwrap(),
                "--overlay-array",
                array,
                "--view",
                "left",
                "--size",
                "48x48",
            ],
            &out,
            &scene,
        );
        (s["meshes"][0]["overlay"]["array"].clone(), decode(&out).3)
    };
    let (a0, img0) = render("0");
    let (a1, img1) = render("1");
    assert_eq!((a0, a1), (0.into(), 1.into()));
    assert_ne!(img0, img1, "the two arrays gave the same picture");
}

#[test]
fn bad_overlays_and_mesh_scenes_fail_with_one_line_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, overlay) = octahedron(dir.path());
    let short = dir.path().join("short.ply");
    std::fs::write(&short, ply_scalars(4)).unwrap();
    let no_scalar = dir.path().join("plain.ply");
    std::fs::write(
        &no_scalar,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    )
    .unwrap();
    let out = dir.path().join("out.png");
    let o = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![&mesh, "--overlay", short.to_str().unwrap()],
            "4 values for the 6 vertices",
        ),
        (
            vec![&mesh, "--overlay", no_scalar.to_str().unwrap()],
            "no vertex scalar",
        ),
        (vec![&mesh, "--overlay", &mesh], "expected a GIFTI"),
        (
            vec![&mesh, "--overlay", &mesh, "--overlay", &mesh],
            "2 overlays for 1 meshes",
        ),
        (
            vec![&mesh, "--colormap", "viridis"],
            "need a mesh with an --overlay",
        ),
        (vec![&mesh, "--ssaa", "3"], "ssaa"),
        (vec![&mesh, "--mode", "mip"], "needs a volume"),
        (vec![&mesh, "--iso", "3"], "iso value needs a volume"),
        (vec!["/nonexistent/lh.pial.gii"], "lh.pial.gii"),
        (vec![&mesh, "--overlay-range", "2,1"], "LO,HI"),
        (
            vec![&mesh, "--overlay", &overlay, "--overlay-array", "1"],
            "array 1: a PLY file has one (0)",
        ),
        (
            vec![&mesh, "--overlay-array", "0"],
            "1 --overlay-array for 0 overlays",
        ),
    ];
    for (argv, needle) in cases {
        let mut args = vec!["render", "-q", "-o", o];
        args.extend_from_slice(&argv);
        let r = glint(&args);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success(), "{argv:?} succeeded");
        assert!(err.contains(needle), "{argv:?}: '{err}' lacks '{needle}'");
        assert_eq!(err.trim_end().lines().count(), 1, "{argv:?}: {err}");
        assert!(!out.exists(), "{argv:?} left {o}");
    }
}
