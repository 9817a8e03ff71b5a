//! OME-Zarr stores written by the Python `ome-zarr` and `zarr` packages
//! (scripts/fixtures/zarr-fixtures.py): every level of each read as zarr-python read it
//! (tests/data/zarr/reference.tsv), the pyramid listed, `Level::Auto` picking the
//! coarsest level with enough voxels, and bad stores refused with one line.

use glint_io::zarr::{self, Level};
use glint_io::{open_volume, Format, IoError, ReadOptions, Samples};

mod common;

use common::{edited_one_level_store, zarr_data as data};

struct Reference {
    store: String,
    level: usize,
    dims: [usize; 3],
    dtype: String,
    scale: [f64; 3],
    sum: i64,
    voxels: Vec<([usize; 3], f64)>,
}

fn reference() -> Vec<Reference> {
    let text = std::fs::read_to_string(data("reference.tsv")).unwrap();
    text.lines()
        .map(|line| {
            let f: Vec<&str> = line.split('\t').collect();
            let three =
                |s: &str| -> Vec<f64> { s.split(' ').map(|x| x.parse().unwrap()).collect() };
            let d = three(f[2]);
            let s = three(f[4]);
            Reference {
                store: f[0].into(),
                level: f[1].parse().unwrap(),
                dims: [d[0] as usize, d[1] as usize, d[2] as usize],
                dtype: f[3].into(),
                scale: [s[0], s[1], s[2]],
                sum: f[5].parse().unwrap(),
                voxels: f[6]
                    .split(' ')
                    .map(|v| {
                        let (ijk, val) = v.split_once('=').unwrap();
                        let ijk: Vec<usize> = ijk.split(',').map(|x| x.parse().unwrap()).collect();
                        ([ijk[0], ijk[1], ijk[2]], val.parse().unwrap())
                    })
                    .collect(),
            }
        })
        .collect()
}

/// Every level of every store, read as zarr-python reads it: sizes, type, voxel size,
/// the sum of all values and eight voxels; Zarr v2 with blosc and gzip, v3 with zstd;
/// a channel axis read at channel 0 with a note.
#[test]
fn every_level_reads_as_zarr_python_reads_it() {
    let refs = reference();
    assert!(refs.len() >= 11, "the reference covers the stores");
    for r in &refs {
        let path = data(&r.store);
        assert_eq!(Format::guess(&path), Some(Format::Zarr));
        let options = ReadOptions {
            level: Level::Index(r.level),
            ..ReadOptions::default()
        };
        let f = open_volume(&path, &options).unwrap();
        let v = &f.volume;
        let what = format!("{} level {}", r.store, r.level);
        assert_eq!(f.format, Format::Zarr);
        assert_eq!(v.dims, r.dims, "{what}");
        assert_eq!(v.spacing, r.scale, "{what}");
        assert_eq!(r.dtype, "uint16");
        assert!(matches!(v.samples, Samples::U16(_)), "{what}");
        let sum: i64 = (0..v.len()).map(|i| v.samples.get(i) as i64).sum();
        assert_eq!(sum, r.sum, "{what}");
        for &([i, j, k], want) in &r.voxels {
            assert_eq!(v.value(i, j, k), want, "{what} ({i}, {j}, {k})");
        }
        let read = f.notes.iter().filter(|n| n.ends_with("(read)")).count();
        assert_eq!(read, 1, "{:?}", f.notes);
        if r.store.contains("czyx") {
            assert!(f
                .notes
                .iter()
                .any(|n| n.contains("first time point and channel")));
        }
    }
}

/// The pyramid as listed, and the level `Auto` picks: the coarsest whose largest edge
/// has at least the pixels asked for.
#[test]
fn levels_are_listed_and_auto_picks_the_coarsest_with_enough_voxels() {
    let levels = zarr::levels(&data("v05-zstd.zarr")).unwrap();
    let dims: Vec<[usize; 3]> = levels.iter().map(|l| l.dims).collect();
    assert_eq!(
        dims,
        [
            [64, 48, 10],
            [32, 24, 10],
            [16, 12, 10],
            [8, 6, 10],
            [4, 3, 10]
        ]
    );
    assert_eq!(levels[2].scale, [4.0, 4.0, 1.0]);
    assert_eq!(zarr::pick(&levels, Level::Auto(16)), Some(2));
    assert_eq!(zarr::pick(&levels, Level::Auto(17)), Some(1));
    assert_eq!(zarr::pick(&levels, Level::Auto(10)), Some(4));
    assert_eq!(zarr::pick(&levels, Level::Auto(1000)), Some(0));
    assert_eq!(zarr::pick(&levels, Level::Index(5)), None);
    let options = ReadOptions {
        level: Level::Index(7),
        ..ReadOptions::default()
    };
    let err = open_volume(&data("v05-zstd.zarr"), &options).unwrap_err();
    assert!(err.to_string().contains("the pyramid has 5"), "{err}");
}

/// Inconsistent pyramid metadata and an unknown codec: one line each, naming the store.
#[test]
fn bad_stores_give_one_clear_line() {
    for (name, says) in [
        ("bad-pyramid.zarr", "finer than the level before it"),
        ("bad-codec.zarr", "no-such-codec"),
    ] {
        let err = open_volume(&data(name), &ReadOptions::default()).unwrap_err();
        let text = err.to_string();
        assert!(matches!(err, IoError::Invalid { .. }), "{text}");
        assert!(text.contains(name), "{text}");
        assert!(text.contains(says), "{text}");
        assert!(!text.contains('\n'), "{text}");
    }
}

/// A store's level larger than `max_voxels` is refused before anything is read.
#[test]
fn a_level_over_the_voxel_limit_is_refused() {
    let options = ReadOptions {
        max_voxels: 1000,
        ..ReadOptions::default()
    };
    let err = open_volume(&data("v04-blosc.zarr"), &options).unwrap_err();
    assert!(matches!(err, IoError::TooLarge { .. }), "{err}");
}

/// A store missing one of its 12 chunks (missing-chunk.zarr: the same data as
/// v04-blosc.zarr's level 0 in chunks of 32 x 16 x 5, the one at x 32.., y 16..32,
/// z 0..5 deleted): read with one note naming how many chunks were missing, that
/// chunk's voxels the fill value 0 and every other voxel as in the whole store; refused
/// with one line under `strict`.
#[test]
fn a_missing_chunk_reads_as_the_fill_value_with_a_note_or_is_refused_strictly() {
    let whole = open_volume(&data("v04-blosc.zarr"), &ReadOptions::default()).unwrap();
    let f = open_volume(&data("missing-chunk.zarr"), &ReadOptions::default()).unwrap();
    let notes: Vec<&String> = f.notes.iter().filter(|n| n.contains("missing")).collect();
    assert_eq!(notes.len(), 1, "{:?}", f.notes);
    assert!(notes[0].contains("1 of 12 chunks missing"), "{}", notes[0]);
    let (v, w) = (&f.volume, &whole.volume);
    assert_eq!(v.dims, [64, 48, 10]);
    for k in 0..10 {
        for j in 0..48 {
            for i in 0..64 {
                let n = i + 64 * (j + 48 * k);
                let gone = i >= 32 && (16..32).contains(&j) && k < 5;
                let want = if gone { 0.0 } else { w.samples.get(n) };
                assert_eq!(v.samples.get(n), want, "voxel {i},{j},{k}");
            }
        }
    }
    let strict = ReadOptions {
        strict: true,
        ..ReadOptions::default()
    };
    let err = open_volume(&data("missing-chunk.zarr"), &strict).unwrap_err();
    let text = err.to_string();
    assert!(text.contains("1 of 12 chunks are missing"), "{text}");
    assert!(!text.contains('\n'), "{text}");
}

/// An absurd chunk shape in a level's metadata (a chunk of 10^27 voxels over a level
/// of 30,720, edited into a copy of v05-zstd.zarr as the fuzz target's inputs edit
/// it): refused in one line before any chunk is read or allocated for.
#[test]
fn an_absurd_chunk_shape_is_refused_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let store = edited_one_level_store(dir.path(), |array| {
        array["chunk_grid"]["configuration"]["chunk_shape"] =
            serde_json::json!([1_000_000_000u64, 1_000_000_000u64, 1_000_000_000u64]);
    });
    std::fs::create_dir_all(store.join("0/c/0/0")).unwrap();
    let src = data("v05-zstd.zarr");
    std::fs::copy(src.join("0/c/0/0/0"), store.join("0/c/0/0/0")).unwrap();
    let err = open_volume(&store, &ReadOptions::default()).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, IoError::TooLarge { .. }), "{text}");
    assert!(text.contains("chunks of"), "{text}");
    assert!(!text.contains('\n'), "{text}");
}
