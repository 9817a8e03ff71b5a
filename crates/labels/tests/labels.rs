//! Label tables, label grids and label surfaces against facts stated independently of
//! the code: FreeSurfer's published LUT, TotalSegmentator's class map, closed-form
//! volumes, and the geometry of shared boundaries.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glint_io::{Mesh, Samples, Volume};
use glint_labels::{
    default_label_smoothing, label_surfaces, label_surfaces_keeping_thin, LabelError, LabelGrid,
    LabelTable, FREESURFER_LUT,
};

#[test]
fn freesurfer_table_has_every_line_of_the_lut() {
    let table = LabelTable::freesurfer();
    // Every line starting with a digit is an entry (counted here without the parser).
    let lines = FREESURFER_LUT
        .lines()
        .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .count();
    assert_eq!(table.len(), lines);
    // Values and colours as FreeSurferColorLUT.txt lists them.
    let e = table.get(17).unwrap();
    assert_eq!(
        (e.name.as_str(), e.color),
        ("Left-Hippocampus", [220, 216, 20])
    );
    assert_eq!(table.get(2).unwrap().color, [245, 245, 245]);
    assert_eq!(table.name_of(1035), "ctx-lh-insula");
    assert_eq!(table.name_of(2035), "ctx-rh-insula");
    assert_eq!(table.lookup("LEFT-HIPPOCAMPUS").unwrap(), 17);
    assert_eq!(table.lookup("53").unwrap(), 53);
}

#[test]
fn totalsegmentator_table_follows_the_class_map() {
    let t = LabelTable::totalsegmentator();
    assert_eq!(t.len(), 117);
    assert_eq!(t.name_of(1), "spleen");
    assert_eq!(t.name_of(5), "liver");
    assert_eq!(t.name_of(52), "aorta");
    assert_eq!(t.name_of(116), "sternum");
    assert_eq!(t.name_of(117), "costal_cartilages");
    assert_eq!(t.lookup("Aorta").unwrap(), 52);
    // Arteries red, veins blue.
    let [r, _, b] = t.color_of(52);
    assert!(r > 150 && b < 100);
    let [r, _, b] = t.color_of(63);
    assert!(b > 150 && r < 100);
    // Values outside the table: named by number, a generated colour.
    assert_eq!(t.name_of(200), "label 200");
    assert_ne!(t.color_of(200), t.color_of(201));
}

#[test]
fn unknown_names_are_refused_with_near_names() {
    let t = LabelTable::totalsegmentator();
    match t.lookup("kidney") {
        Err(LabelError::UnknownLabel { hint, .. }) => {
            assert!(hint.contains("kidney_right"), "{hint}")
        }
        other => panic!("{other:?}"),
    }
    assert!(t.lookup("nothing-like-it").is_err());
    // A typo: names within two edits.
    let hint = t.lookup("livr").unwrap_err().to_string();
    assert!(hint.contains("did you mean liver"), "{hint}");
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn tables_are_read_from_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let lut = write(
        d,
        "my.txt",
        "# comment\n\n0 Unknown 0 0 0 0\n7 Tumour 255 0 0 0\n",
    );
    let t = LabelTable::read(&lut).unwrap();
    assert_eq!(
        (t.name_of(7), t.color_of(7)),
        ("Tumour".into(), [255, 0, 0])
    );
    let ctbl = write(
        d,
        "s.ctbl",
        "# Color table file s.ctbl\n# 2 values\n0 background 0 0 0 0\n3 liver 128 64 32 255\n",
    );
    assert_eq!(LabelTable::read(&ctbl).unwrap().color_of(3), [128, 64, 32]);
    let json = write(
        d,
        "t.json",
        r#"{"4": "spleen", "9": {"name": "aorta", "color": [200, 10, 20]}}"#,
    );
    let t = LabelTable::read(&json).unwrap();
    assert_eq!(t.name_of(4), "spleen");
    assert_eq!(t.color_of(9), [200, 10, 20]);
    let csv = write(
        d,
        "s.csv",
        "group,original_idx,structure,id\norgans,1,spleen,1\nribs,26,costal_cartilages,118\n",
    );
    let t = LabelTable::read(&csv).unwrap();
    assert_eq!(t.name_of(118), "costal_cartilages");
    assert_eq!(
        LabelTable::open("freesurfer").unwrap().name_of(17),
        "Left-Hippocampus"
    );
}

#[test]
fn malformed_tables_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (name, text, want) in [
        ("a.txt", "1 ok 1 2 3 0\n2 bad 1 2\n", "line 2"),
        ("b.txt", "1 red 300 0 0 0\n", "300"),
        ("c.txt", "x name 1 2 3 0\n", "whole number"),
        ("d.json", "[1, 2]", "expected an object"),
        (
            "e.json",
            r#"{"1": {"name": "a", "color": [1, 2]}}"#,
            "color",
        ),
        ("f.csv", "a,b\n1,2\n", "header"),
        ("g.csv", "id,name\n1,a,extra\n", "line 2"),
    ] {
        let err = LabelTable::read(&write(d, name, text))
            .unwrap_err()
            .to_string();
        assert!(err.contains(want), "{name}: {err}");
        assert!(err.contains(name), "{name}: {err}");
    }
    assert!(LabelTable::open("no-such-table.txt").is_err());
}

fn volume(dims: [usize; 3], spacing: [f64; 3], f: impl Fn(usize, usize, usize) -> u8) -> Volume {
    let v = (0..dims.iter().product::<usize>())
        .map(|i| f(i % dims[0], i / dims[0] % dims[1], i / (dims[0] * dims[1])))
        .collect();
    Volume::new(dims, spacing, Samples::U8(v)).unwrap()
}

#[test]
fn summary_counts_and_boxes_match_a_brute_force_pass() {
    let vol = volume([13, 9, 7], [2.0, 3.0, 4.0], |x, y, z| {
        ((x * 7 + y * 3 + z) % 5) as u8
    });
    let grid = LabelGrid::from_volume(&vol).unwrap();
    let summary = grid.summary();
    let mut brute: HashMap<u32, (u64, [usize; 3], [usize; 3])> = HashMap::new();
    for z in 0..7 {
        for y in 0..9 {
            for x in 0..13 {
                let v = ((x * 7 + y * 3 + z) % 5) as u32;
                if v == 0 {
                    continue;
                }
                let e = brute.entry(v).or_insert((0, [x, y, z], [x, y, z]));
                e.0 += 1;
                e.1 = [e.1[0].min(x), e.1[1].min(y), e.1[2].min(z)];
                e.2 = [e.2[0].max(x), e.2[1].max(y), e.2[2].max(z)];
            }
        }
    }
    assert_eq!(summary.len(), brute.len());
    for (v, e) in &summary {
        assert_eq!((e.voxels, e.lo, e.hi), brute[v], "label {v}");
    }
    // 2 x 3 x 4 mm voxels: 24 mm^3 = 0.024 ml.
    assert!((grid.voxel_ml() - 0.024).abs() < 1e-12);
}

#[test]
fn non_label_volumes_are_refused_with_the_reason() {
    let mut v = Volume::new([2, 1, 1], [1.0; 3], Samples::F32(vec![1.0, 2.5])).unwrap();
    let err = LabelGrid::from_volume(&v).unwrap_err().to_string();
    assert!(
        err.contains("(1, 0, 0) is 2.5") && err.contains("whole numbers"),
        "{err}"
    );
    v.samples = Samples::F32(vec![-1.0, 2.0]);
    assert!(LabelGrid::from_volume(&v).is_err());
    v.samples = Samples::F32(vec![f32::NAN, 2.0]);
    assert!(LabelGrid::from_volume(&v).is_err());
    // Scaled integers are labels when the physical values are whole.
    let mut s = Volume::new([2, 1, 1], [1.0; 3], Samples::I16(vec![1, 2])).unwrap();
    s.slope = 2.0;
    assert_eq!(LabelGrid::from_volume(&s).unwrap().labels, vec![2, 4]);
    s.slope = 0.5;
    assert!(LabelGrid::from_volume(&s).is_err());
}

/// The volume a closed, outward-oriented mesh encloses (divergence theorem).
fn enclosed_volume(m: &Mesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].map(f64::from));
            let cross = [
                b[1] * c[2] - b[2] * c[1],
                b[2] * c[0] - b[0] * c[2],
                b[0] * c[1] - b[1] * c[0],
            ];
            (a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2]) / 6.0
        })
        .sum()
}

/// Every edge is shared by exactly two triangles, in opposite directions.
fn is_closed(m: &Mesh) -> bool {
    let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    edges
        .iter()
        .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
}

#[test]
fn a_ball_label_gives_a_closed_surface_of_the_balls_volume() {
    // A ball of radius 8 mm on 1 x 1 x 2 mm voxels, touching nothing.
    let r = 8.0;
    let vol = volume([24, 24, 12], [1.0, 1.0, 2.0], |x, y, z| {
        let p = [x as f64 - 11.5, y as f64 - 11.5, (z as f64 - 5.5) * 2.0];
        u8::from(p.iter().map(|c| c * c).sum::<f64>() < r * r) * 3
    });
    let grid = LabelGrid::from_volume(&vol).unwrap();
    let (_, mesh) = label_surfaces(&grid, &[3], 0.5).unwrap().remove(0);
    assert!(is_closed(&mesh));
    let want = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let got = enclosed_volume(&mesh);
    assert!((got / want - 1.0).abs() < 0.06, "volume {got} vs {want}");
    // Outward: positive enclosed volume, and the vertices lie near the sphere.
    for p in &mesh.positions {
        let d = ((p[0] as f64 - 11.5).powi(2)
            + (p[1] as f64 - 11.5).powi(2)
            + (p[2] as f64 - 11.0).powi(2))
        .sqrt();
        assert!((d - r).abs() < 1.5, "vertex at radius {d}");
    }
}

#[test]
fn a_label_on_the_grid_border_is_closed_there() {
    let vol = volume([6, 6, 6], [1.0; 3], |x, _, _| u8::from(x < 3));
    let grid = LabelGrid::from_volume(&vol).unwrap();
    let (_, mesh) = label_surfaces(&grid, &[1], 1.0).unwrap().remove(0);
    assert!(is_closed(&mesh));
    assert!(enclosed_volume(&mesh) > 0.0);
}

#[test]
fn two_labels_share_their_boundary_without_a_gap() {
    // Labels 1 and 2 fill a block, split at x = 7.5; everything else is background.
    let vol = volume([16, 10, 10], [1.0; 3], |x, y, z| {
        let inside = (2..8).contains(&y) && (2..8).contains(&z) && (2..14).contains(&x);
        match (inside, x < 8) {
            (true, true) => 1,
            (true, false) => 2,
            _ => 0,
        }
    });
    let grid = LabelGrid::from_volume(&vol).unwrap();
    let mut s = label_surfaces(&grid, &[1, 2, 9], 1.0).unwrap();
    assert_eq!(s.len(), 2, "label 9 is absent");
    let (_, b) = s.pop().unwrap();
    let (_, a) = s.pop().unwrap();
    // A's vertices on the shared plane (x = 7.5, away from the block's outer faces,
    // where three labels meet) each have a B vertex at the same place.
    let mut shared = 0;
    for p in a.positions.iter().filter(|p| (p[0] - 7.5).abs() < 0.01) {
        // The block spans y, z in 2..=7: its middle, away from the outer faces.
        if !(3.0..=6.0).contains(&p[1]) || !(3.0..=6.0).contains(&p[2]) {
            continue;
        }
        shared += 1;
        let d = b
            .positions
            .iter()
            .map(|q| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f32>())
            .fold(f32::INFINITY, f32::min);
        assert!(d.sqrt() < 1e-4, "A vertex {p:?} is {} mm from B", d.sqrt());
    }
    assert!(shared >= 16, "{shared} vertices on the shared face");
}

#[test]
fn smoothing_out_of_range_is_refused() {
    let vol = volume([4, 4, 4], [1.0; 3], |_, _, _| 1);
    let grid = LabelGrid::from_volume(&vol).unwrap();
    for s in [-1.0, f32::NAN, 100.0] {
        assert!(matches!(
            label_surfaces(&grid, &[1], s),
            Err(LabelError::Parameter(_))
        ));
    }
}

#[test]
fn table_alpha_from_freesurfer_slicer_and_json() {
    // FreeSurfer's fourth colour column is a transparency (alpha = 255 - t,
    // FreeSurfer's colortab.c); Slicer's is an opacity; absent: opaque.
    let fs = LabelTable::parse_lut(
        "17 Hippo 220 216 20 64\n18 Amyg 103 255 255\n",
        Path::new("fs.txt"),
        false,
    )
    .unwrap();
    assert_eq!((fs.alpha_of(17), fs.alpha_of(18)), (191, 255));
    let slicer = LabelTable::parse_lut(
        "1 liver 200 100 90 128\n2 aorta 220 40 40\n",
        Path::new("t.ctbl"),
        true,
    )
    .unwrap();
    assert_eq!((slicer.alpha_of(1), slicer.alpha_of(2)), (128, 255));
    // A value not in the table is opaque.
    assert_eq!(slicer.alpha_of(9), glint_labels::OPAQUE);
    let json = LabelTable::parse_json(
        r#"{"1": {"name": "liver", "alpha": 0.5}, "2": "aorta"}"#,
        Path::new("t.json"),
    )
    .unwrap();
    assert_eq!((json.alpha_of(1), json.alpha_of(2)), (128, 255));
    let err = LabelTable::parse_json(
        r#"{"1": {"name": "liver", "alpha": 2}}"#,
        Path::new("t.json"),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("\"alpha\" must be in 0..=1"), "{err}");
    // FreeSurfer's own LUT: every structure opaque (its column is 0 throughout).
    let fs = LabelTable::freesurfer();
    assert!(fs.entries().all(|(_, e)| e.alpha == 255));
}

#[test]
fn the_default_smoothing_follows_the_slices_against_the_pixels() {
    // Isotropic grids (and nearly: rounding in a header) keep one voxel: their images
    // stay as they were.
    for spacing in [[1.0; 3], [0.98, 1.0, 1.0], [0.5, 0.5, 0.75], [3.0; 3]] {
        assert_eq!(default_label_smoothing(spacing), 1.0, "{spacing:?}");
    }
    // Thick slices: the chest sample's 2.5 mm under 0.703 mm pixels, an abdominal
    // CT's 3 mm under 0.8 mm.
    assert_eq!(default_label_smoothing([0.703, 0.703, 2.5]), 2.0);
    assert_eq!(default_label_smoothing([0.8, 3.0, 0.8]), 2.0);
    assert_eq!(default_label_smoothing([1.0, 1.0, 2.0]), 1.5);
    // A degenerate spacing (refused when a grid is read) falls back to one voxel.
    assert_eq!(default_label_smoothing([0.0, 1.0, 1.0]), 1.0);
}

/// The RMS angle (degrees) between the normals of `m`'s vertices on the tilted top
/// of the slab below and the slab's true normal (vertices at least 12 mm inside the
/// grid's sides in x and y, facing up).
fn terrace_rms(m: &Mesh, slope: f64, side: f32) -> f64 {
    let n = m.normals.as_ref().unwrap();
    let truth = {
        let l = (1.0 + slope * slope).sqrt();
        [-slope / l, 0.0, 1.0 / l]
    };
    let angles: Vec<f64> = (m.positions.iter().zip(n))
        .filter(|(p, n)| {
            (12.0..side - 12.0).contains(&p[0]) && (12.0..side - 12.0).contains(&p[1]) && n[2] > 0.5
        })
        .map(|(_, n)| {
            let dot: f64 = (0..3).map(|a| f64::from(n[a]) * truth[a]).sum();
            dot.clamp(-1.0, 1.0).acos().to_degrees()
        })
        .collect();
    assert!(angles.len() > 100, "{} vertices on the top", angles.len());
    (angles.iter().map(|a| a * a).sum::<f64>() / angles.len() as f64).sqrt()
}

#[test]
fn the_default_smoothing_removes_the_terraces_of_thick_slices() {
    // A slab whose top rises 1 mm per 5 mm in x (11 degrees from the slices), on 3 mm
    // slices under 0.75 mm pixels: its voxels are terraces 3 mm high, 15 mm wide.
    let slope = 0.2;
    let (nxy, nz) = (96, 14);
    let spacing = [0.75, 0.75, 3.0];
    let vol = volume([nxy, nxy, nz], spacing, |x, _, z| {
        let (xm, zm) = (x as f64 * spacing[0], z as f64 * spacing[2]);
        u8::from(zm < 12.0 + slope * xm)
    });
    let grid = LabelGrid::from_volume(&vol).unwrap();
    let side = (nxy - 1) as f32 * 0.75;
    let rms = |s: f32| terrace_rms(&label_surfaces(&grid, &[1], s).unwrap()[0].1, slope, side);
    let (one, default) = (rms(1.0), rms(default_label_smoothing(grid.spacing())));
    // Terrace bands: one voxel leaves half the staircase's ripple (its first harmonic
    // damped by exp(-2 pi^2 0.2^2) = 0.45), two voxels 4% of it.
    assert!(
        one > 3.0 * default,
        "RMS {one:.2} deg at 1 voxel, {default:.2} at the default"
    );
    assert!(default < 2.0, "RMS {default:.2} deg at the default");
}

#[test]
fn thin_labels_keep_one_voxels_smoothing() {
    // On 3 mm slices under 0.75 mm pixels: label 1 a rod 9 mm across (3 slices, 12
    // pixels) running along x (a vessel, a rib), label 2 a block 60 mm on a side beside
    // it (an organ: a Gaussian of 6 mm rounds its edges off, losing 9% of its voxels).
    let spacing = [0.75, 0.75, 3.0];
    let vol = volume([96, 120, 22], spacing, |x, y, z| {
        if (8..88).contains(&x) && (8..20).contains(&y) && (10..13).contains(&z) {
            1
        } else if (8..88).contains(&x) && (32..112).contains(&y) && (1..21).contains(&z) {
            2
        } else {
            0
        }
    });
    let grid = LabelGrid::from_volume(&vol).unwrap();
    let s = default_label_smoothing(grid.spacing());
    assert_eq!(s, 2.0);
    // A Gaussian of 6 mm removes the rod (its blurred indicator stays under 1/2)...
    let raw = label_surfaces(&grid, &[1, 2], s).unwrap();
    assert!(
        raw[0].1.triangles.is_empty(),
        "the rod survived a 6 mm blur"
    );
    // ...so it keeps one voxel's (3 mm), which keeps it; the block keeps the default.
    let kept = label_surfaces_keeping_thin(&grid, &[1, 2], s, 1.0).unwrap();
    let one = label_surfaces(&grid, &[1], 1.0).unwrap();
    assert_eq!((kept[0].0, kept[0].2), (1, 1.0));
    assert_eq!(kept[0].1, one[0].1);
    assert!(is_closed(&kept[0].1) && enclosed_volume(&kept[0].1) > 0.0);
    assert_eq!((kept[1].0, kept[1].2), (2, 2.0));
    assert_eq!(kept[1].1, raw[1].1);
    // With a fallback equal to the smoothing nothing changes.
    let same = label_surfaces_keeping_thin(&grid, &[1, 2], 1.0, 1.0).unwrap();
    assert!(same.iter().zip(&one).all(|(a, b)| a.0 == b.0 && a.2 == 1.0));
}
