//! Writes one volume and one mesh with every glint-io writer into a directory, so that
//! readers glint did not write (nibabel, pynrrd, plyfile: crates/python/tests/
//! test_writers.py) can check the files (issue 34).
//!
//! `cargo run -p glint-io --example write_formats DIR`
//!
//! The volume: 4 x 3 x 2 int16, value(i, j, k) = i + 10 j + 100 k - 50, slope 2,
//! intercept 1 (NIfTI only: NRRD has no scaling), affine rows (0 0 -2.5 10),
//! (1.5 0 0 -4), (0 2 0 7.25). The mesh: the tetrahedron (0,0,0), (10,0,0), (0,20,0),
//! (0,0,30) with outward triangles (0,2,1), (0,1,3), (0,3,2), (1,2,3), per-vertex
//! normals (0,0,-1), (1,0,0), (0,1,0), (0,0,1) and scalars 0.5, 1.5, 2.5, 3.5. The
//! test states the same values independently.
use std::path::Path;

use glint_io::mesh::{write_ply, PlyEncoding};
use glint_io::{gifti, nifti, nrrd, Endian, Mesh, Samples, Volume};

fn volume() -> Result<Volume, glint_io::IoError> {
    let mut v = Vec::new();
    for k in 0..2i16 {
        for j in 0..3i16 {
            for i in 0..4i16 {
                v.push(i + 10 * j + 100 * k - 50);
            }
        }
    }
    let mut vol = Volume::new([4, 3, 2], [1.5, 2.0, 2.5], Samples::I16(v))?;
    vol.affine = [
        [0.0, 0.0, -2.5, 10.0],
        [1.5, 0.0, 0.0, -4.0],
        [0.0, 2.0, 0.0, 7.25],
        [0.0, 0.0, 0.0, 1.0],
    ];
    vol.slope = 2.0;
    vol.intercept = 1.0;
    Ok(vol)
}

fn mesh() -> Mesh {
    Mesh {
        positions: vec![
            [0.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [0.0, 20.0, 0.0],
            [0.0, 0.0, 30.0],
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        normals: Some(vec![
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]),
        scalars: Some(vec![0.5, 1.5, 2.5, 3.5]),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(dir) = std::env::args_os().nth(1) else {
        eprintln!("usage: write_formats DIR");
        std::process::exit(2);
    };
    let dir = Path::new(&dir);
    std::fs::create_dir_all(dir)?;
    let vol = volume()?;
    nifti::write(&dir.join("vol.nii"), &vol, false, Endian::Little)?;
    nifti::write(&dir.join("vol_be.nii.gz"), &vol, true, Endian::Big)?;
    nrrd::write(
        &dir.join("vol.nrrd"),
        &vol,
        nrrd::Encoding::Raw,
        Endian::Little,
    )?;
    nrrd::write(
        &dir.join("vol_gz.nrrd"),
        &vol,
        nrrd::Encoding::Gzip,
        Endian::Big,
    )?;
    nrrd::write_detached(
        &dir.join("vol.nhdr"),
        &vol,
        nrrd::Encoding::Raw,
        Endian::Little,
    )?;
    let m = mesh();
    write_ply(
        &dir.join("mesh_le.ply"),
        &m,
        PlyEncoding::BinaryLittleEndian,
    )?;
    write_ply(&dir.join("mesh_be.ply"), &m, PlyEncoding::BinaryBigEndian)?;
    write_ply(&dir.join("mesh_ascii.ply"), &m, PlyEncoding::Ascii)?;
    gifti::write(&dir.join("mesh_ascii.gii"), &m, gifti::Encoding::Ascii)?;
    gifti::write(&dir.join("mesh_b64.gii"), &m, gifti::Encoding::Base64)?;
    gifti::write(&dir.join("mesh_gz.gii"), &m, gifti::Encoding::GzipBase64)?;
    Ok(())
}
