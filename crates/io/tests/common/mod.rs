//! Helpers shared by the integration tests: sample-data lookup and hand-built headers.
#![allow(dead_code)]

pub mod table;

use std::path::{Path, PathBuf};

/// The directory scripts/fetch-samples fills (`$GLINT_DATA/samples`).
pub fn samples_dir() -> PathBuf {
    glint_testkit::samples_dir()
}

/// A sample file; `None` (after saying why) when it is missing, a failure naming it
/// in strict mode (`GLINT_STRICT` or `CI` set: glint_testkit).
pub fn sample(name: &str) -> Option<PathBuf> {
    glint_testkit::sample(name)
}

/// A NIfTI-1 header written field by field from nifti1.h offsets, independent of the
/// crate's writer.
pub struct NiftiHeader {
    pub big_endian: bool,
    pub dim: [i16; 8],
    pub datatype: i16,
    pub bitpix: i16,
    pub pixdim: [f32; 8],
    pub vox_offset: f32,
    pub scl_slope: f32,
    pub scl_inter: f32,
    pub xyzt_units: u8,
    pub qform_code: i16,
    pub sform_code: i16,
    pub quatern: [f32; 6],
    pub srow: [[f32; 4]; 3],
    pub magic: [u8; 4],
}

impl NiftiHeader {
    pub fn new(dims: [i16; 3], datatype: i16, bitpix: i16) -> Self {
        NiftiHeader {
            big_endian: false,
            dim: [3, dims[0], dims[1], dims[2], 1, 1, 1, 1],
            datatype,
            bitpix,
            pixdim: [1.0; 8],
            vox_offset: 352.0,
            scl_slope: 1.0,
            scl_inter: 0.0,
            xyzt_units: 2,
            qform_code: 0,
            sform_code: 0,
            quatern: [0.0; 6],
            srow: [[0.0; 4]; 3],
            magic: *b"n+1\0",
        }
    }

    pub fn bytes(&self) -> Vec<u8> {
        let mut b = vec![0u8; 352];
        let be = self.big_endian;
        let i16b = |v: i16| if be { v.to_be_bytes() } else { v.to_le_bytes() };
        let f32b = |v: f32| if be { v.to_be_bytes() } else { v.to_le_bytes() };
        b[0..4].copy_from_slice(&if be {
            348i32.to_be_bytes()
        } else {
            348i32.to_le_bytes()
        });
        for i in 0..8 {
            b[40 + 2 * i..42 + 2 * i].copy_from_slice(&i16b(self.dim[i]));
            b[76 + 4 * i..80 + 4 * i].copy_from_slice(&f32b(self.pixdim[i]));
        }
        b[70..72].copy_from_slice(&i16b(self.datatype));
        b[72..74].copy_from_slice(&i16b(self.bitpix));
        b[108..112].copy_from_slice(&f32b(self.vox_offset));
        b[112..116].copy_from_slice(&f32b(self.scl_slope));
        b[116..120].copy_from_slice(&f32b(self.scl_inter));
        b[123] = self.xyzt_units;
        b[252..254].copy_from_slice(&i16b(self.qform_code));
        b[254..256].copy_from_slice(&i16b(self.sform_code));
        for i in 0..6 {
            b[256 + 4 * i..260 + 4 * i].copy_from_slice(&f32b(self.quatern[i]));
        }
        for r in 0..3 {
            for c in 0..4 {
                let at = 280 + 16 * r + 4 * c;
                b[at..at + 4].copy_from_slice(&f32b(self.srow[r][c]));
            }
        }
        b[344..348].copy_from_slice(&self.magic);
        b
    }
}

pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

/// Asserts two affines agree to `tol`.
pub fn assert_affine_eq(a: &[[f64; 4]; 4], b: &[[f64; 4]; 4], tol: f64) {
    for r in 0..4 {
        for c in 0..4 {
            assert!(
                (a[r][c] - b[r][c]).abs() <= tol,
                "affine[{r}][{c}]: {} vs {}\n{a:?}\n{b:?}",
                a[r][c],
                b[r][c]
            );
        }
    }
}

/// A Zarr test store written by scripts/fixtures/zarr-fixtures.py (tests/data/zarr).
pub fn zarr_data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/zarr")
        .join(name)
}

/// A copy of `v05-zstd.zarr`'s group with its first level only, in `dir`, the level's
/// array metadata changed by `edit` (no chunk copied): a store with metadata a test
/// needs. Returns the store's path.
pub fn edited_one_level_store(dir: &Path, edit: impl FnOnce(&mut serde_json::Value)) -> PathBuf {
    let store = dir.join("s.zarr");
    let src = zarr_data("v05-zstd.zarr");
    std::fs::create_dir_all(store.join("0")).unwrap();
    let mut group: serde_json::Value =
        serde_json::from_slice(&std::fs::read(src.join("zarr.json")).unwrap()).unwrap();
    let datasets = &mut group["attributes"]["ome"]["multiscales"][0]["datasets"];
    datasets.as_array_mut().unwrap().truncate(1);
    std::fs::write(store.join("zarr.json"), group.to_string()).unwrap();
    let mut array: serde_json::Value =
        serde_json::from_slice(&std::fs::read(src.join("0/zarr.json")).unwrap()).unwrap();
    edit(&mut array);
    std::fs::write(store.join("0/zarr.json"), array.to_string()).unwrap();
    store
}
