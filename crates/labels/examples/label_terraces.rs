//! Measures what a label smoothing does to a label map's surfaces (issue 42, item
//! 6c): the terraces of thick slices on a smooth organ, as the RMS angle between each
//! vertex normal and the mean normal of the surface within 6 mm of it, and what it
//! does to thin structures (enclosed volume against the voxels', pieces, labels whose
//! surface vanishes).
//!
//! `cargo run -p glint-labels --example label_terraces -- MASK SMOOTH_ORGAN
//! THIN,LABELS S1 [S2 ...]` (label numbers; smoothings in voxels of the coarsest axis,
//! or `default`).

use std::collections::HashMap;
use std::path::Path;

use glint_io::{read_volume, Mesh, ReadOptions};
use glint_labels::{default_label_smoothing, label_surfaces_keeping_thin, LabelGrid};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 4 {
        return Err("usage: label_terraces MASK SMOOTH_ORGAN THIN,LABELS S1 [S2 ...]".into());
    }
    let volume = read_volume(Path::new(&args[0]), &ReadOptions::default())?;
    let grid = LabelGrid::from_volume(&volume)?;
    drop(volume);
    let organ: u32 = args[1].parse()?;
    let thin: Vec<u32> = args[2]
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let summary = grid.summary();
    let all: Vec<u32> = summary.keys().copied().collect();
    let mm3 = grid.voxel_ml() * 1000.0;
    println!(
        "spacing {:?} mm, {} labels; default smoothing {}",
        grid.spacing(),
        all.len(),
        default_label_smoothing(grid.spacing())
    );
    for s in &args[3..] {
        let smoothing = match s.as_str() {
            "default" => default_label_smoothing(grid.spacing()),
            s => s.parse()?,
        };
        let t = std::time::Instant::now();
        // As the renderer extracts them: thin labels keep one voxel's smoothing at most.
        let meshes = label_surfaces_keeping_thin(&grid, &all, smoothing, smoothing.min(1.0))?;
        let seconds = t.elapsed().as_secs_f64();
        let vanished: Vec<u32> = (meshes.iter())
            .filter(|(_, m, _)| m.triangles.is_empty())
            .map(|(v, _, _)| *v)
            .collect();
        let fell_back: Vec<u32> = (meshes.iter())
            .filter(|(_, _, s)| *s != smoothing)
            .map(|(v, _, _)| *v)
            .collect();
        println!("smoothing {smoothing}: {seconds:.1} s, vanished labels {vanished:?}");
        println!(
            "  labels kept at smoothing {}: {fell_back:?}",
            smoothing.min(1.0)
        );
        for (v, m, _) in &meshes {
            if *v == organ {
                let (rms, p95) = roughness(m, 6.0);
                println!(
                    "  label {v}: normal vs its 6 mm mean: RMS {rms:.2} deg, 95th percentile {p95:.2} deg ({} vertices)",
                    m.positions.len()
                );
            }
            if thin.contains(v) {
                let voxels = summary[v].voxels as f64 * mm3;
                println!(
                    "  label {v}: volume {:.0} mm3 of the voxels' {voxels:.0} ({:.0}%), {} pieces",
                    enclosed(m),
                    100.0 * enclosed(m) / voxels,
                    pieces(m)
                );
            }
        }
    }
    Ok(())
}

/// RMS and 95th percentile (degrees) of the angle between each vertex normal and the
/// mean of the vertex normals within `radius` mm.
fn roughness(m: &Mesh, radius: f32) -> (f64, f64) {
    let normals = m.normals.as_ref().expect("marching cubes gives normals");
    let cell = |p: &[f32; 3]| p.map(|x| (x / radius).floor() as i32);
    let mut cells: HashMap<[i32; 3], Vec<usize>> = HashMap::new();
    for (i, p) in m.positions.iter().enumerate() {
        cells.entry(cell(p)).or_default().push(i);
    }
    let mut angles: Vec<f64> = (m.positions.iter().enumerate())
        .map(|(i, p)| {
            let c = cell(p);
            let mut mean = [0.0f64; 3];
            for d in 0..27 {
                let k = [c[0] + d % 3 - 1, c[1] + d / 3 % 3 - 1, c[2] + d / 9 - 1];
                for &j in cells.get(&k).map(Vec::as_slice).unwrap_or(&[]) {
                    let q = m.positions[j];
                    let r2: f32 = (0..3).map(|a| (q[a] - p[a]).powi(2)).sum();
                    if r2 <= radius * radius {
                        for a in 0..3 {
                            mean[a] += f64::from(normals[j][a]);
                        }
                    }
                }
            }
            let len = mean.iter().map(|x| x * x).sum::<f64>().sqrt();
            let dot: f64 = (0..3)
                .map(|a| mean[a] / len * f64::from(normals[i][a]))
                .sum();
            dot.clamp(-1.0, 1.0).acos().to_degrees()
        })
        .collect();
    let rms = (angles.iter().map(|a| a * a).sum::<f64>() / angles.len() as f64).sqrt();
    angles.sort_by(f64::total_cmp);
    (rms, angles[angles.len() * 95 / 100])
}

/// The volume a closed mesh encloses, mm³ (divergence theorem).
fn enclosed(m: &Mesh) -> f64 {
    let p = |i: u32| m.positions[i as usize].map(f64::from);
    (m.triangles.iter())
        .map(|t| {
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

/// Connected pieces of a mesh (triangles sharing a vertex).
fn pieces(m: &Mesh) -> usize {
    let mut parent: Vec<usize> = (0..m.positions.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for t in &m.triangles {
        let a = root(&mut parent, t[0] as usize);
        for &v in &t[1..] {
            let b = root(&mut parent, v as usize);
            parent[b] = a;
        }
    }
    let mut roots: Vec<usize> = (m.triangles.iter())
        .map(|t| root(&mut parent, t[0] as usize))
        .collect();
    roots.sort_unstable();
    roots.dedup();
    roots.len()
}
