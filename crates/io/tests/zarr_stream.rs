//! `zarr::Stream`: boxes of an OME-Zarr level read through the bounded chunk cache
//! equal the level read whole voxel for voxel (boxes straddling chunk edges and
//! reaching past the faces, clamped), the cache never holds more than its bound, a
//! missing chunk reads as the fill value with the whole read's note (refused under
//! `strict`), and a corrupt chunk is reported as one line.

use glint_io::zarr::{Level, Stream};
use glint_io::{open_volume, ReadOptions, Volume};

mod common;

use common::{edited_one_level_store, zarr_data as data};

fn at_level(level: usize) -> ReadOptions {
    ReadOptions {
        level: Level::Index(level),
        ..ReadOptions::default()
    }
}

/// The box `lo .. lo + size` of `v`, clamped to its faces, as f32.
fn expected(v: &Volume, lo: [isize; 3], size: [usize; 3]) -> Vec<f32> {
    let c = |x: isize, n: usize| x.clamp(0, n as isize - 1) as usize;
    let [nx, ny, nz] = v.dims;
    let mut out = Vec::with_capacity(size.iter().product());
    for k in 0..size[2] {
        for j in 0..size[1] {
            for i in 0..size[0] {
                let (i, j, k) = (
                    c(lo[0] + i as isize, nx),
                    c(lo[1] + j as isize, ny),
                    c(lo[2] + k as isize, nz),
                );
                out.push(v.samples.get(i + nx * (j + ny * k)) as f32);
            }
        }
    }
    out
}

/// Boxes of a level of `dims`: the whole level with a margin past every face, single
/// voxels at the corners, and 60 boxes of 1 to 20 voxels a side at positions from a
/// fixed linear congruential sequence (from 5 voxels before a face to past the far
/// one), which straddle chunk edges.
fn boxes(dims: [usize; 3]) -> Vec<([isize; 3], [usize; 3])> {
    let mut out = vec![
        ([-3, -2, -1], dims.map(|d| d + 5)),
        ([0, 0, 0], [1, 1, 1]),
        (dims.map(|d| d as isize - 1), [1, 1, 1]),
    ];
    let mut state = 12345u64;
    let mut next = |n: usize| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 33) % n as u64) as usize
    };
    for _ in 0..60 {
        let lo = dims.map(|d| next(d + 10) as isize - 5);
        let size = [0; 3].map(|_| 1 + next(20));
        out.push((lo, size));
    }
    out
}

/// Every level of every store, through a cache of one chunk (every box evicts), two
/// chunks and the default: each box equals the whole read, and the cache never holds
/// more chunks than its bound allows.
#[test]
fn boxes_equal_the_whole_level_and_the_cache_keeps_its_bound() {
    for (store, levels) in [
        ("v04-blosc.zarr", 5),
        ("v05-zstd.zarr", 5),
        ("v04-gzip-czyx.zarr", 1),
    ] {
        for level in 0..levels {
            let whole = open_volume(&data(store), &at_level(level)).unwrap().volume;
            let chunk = Stream::open(&data(store), &at_level(level), 0, 1)
                .unwrap()
                .chunk_bytes();
            for limit in [0, 2 * chunk, u64::MAX] {
                let s = Stream::open(&data(store), &at_level(level), limit, 2).unwrap();
                assert_eq!(s.dims(), whole.dims);
                assert_eq!(s.affine(), whole.affine);
                let most = (s.cache_bound() / s.chunk_bytes()) as usize;
                assert!(most >= 1);
                if limit == 0 {
                    assert_eq!(most, 1, "{store} {level}");
                } else if limit < u64::MAX {
                    assert!(most <= 2, "{store} {level}: {most} chunks");
                }
                for (lo, size) in boxes(whole.dims) {
                    let mut out = vec![f32::NAN; size.iter().product()];
                    s.read_box(lo, size, &mut out);
                    let want = expected(&whole, lo, size);
                    assert!(
                        out == want,
                        "{store} level {level} box {lo:?} + {size:?} (limit {limit})"
                    );
                    assert!(
                        s.cached_chunks() <= most,
                        "{store} level {level}: {} chunks cached, bound {most}",
                        s.cached_chunks()
                    );
                }
                assert_eq!(s.problem(), None);
            }
        }
    }
}

/// The stream of missing-chunk.zarr notes the missing chunk as the whole read does,
/// reads it as the fill value (the whole read's values), and is refused under
/// `strict` with the whole read's line.
#[test]
fn a_missing_chunk_reads_as_the_fill_value_with_the_same_note() {
    let path = data("missing-chunk.zarr");
    let whole = open_volume(&path, &ReadOptions::default()).unwrap();
    let s = Stream::open(&path, &ReadOptions::default(), 0, 1).unwrap();
    assert_eq!(s.notes(), &whole.notes[..]);
    assert!(s
        .notes()
        .iter()
        .any(|n| n.contains("1 of 12 chunks missing")));
    let size = whole.volume.dims;
    let mut out = vec![f32::NAN; size.iter().product()];
    s.read_box([0, 0, 0], size, &mut out);
    assert!(out == expected(&whole.volume, [0, 0, 0], size));
    // The missing chunk (x 32.., y 16..32, z 0..5) is the fill value 0.
    assert_eq!(out[40 + 64 * (20 + 48 * 2)], 0.0);
    let strict = ReadOptions {
        strict: true,
        ..ReadOptions::default()
    };
    let err = Stream::open(&path, &strict, 0, 1)
        .err()
        .unwrap()
        .to_string();
    let whole_err = open_volume(&path, &strict).unwrap_err().to_string();
    assert_eq!(err, whole_err);
    assert!(err.contains("1 of 12 chunks are missing"), "{err}");
}

/// A chunk whose bytes are not blosc: the box that needs it is reported through
/// `problem` as one line naming the store and level; boxes that do not need it read.
#[test]
fn a_corrupt_chunk_is_one_line_of_problem() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("c.zarr");
    glint_testkit::copy_dir(&data("missing-chunk.zarr"), &store);
    // The chunk at x 0..32, y 0..16, z 0..5.
    std::fs::write(store.join("0/0/0/0"), b"not a blosc chunk").unwrap();
    let s = Stream::open(&store, &ReadOptions::default(), 0, 1).unwrap();
    let mut out = vec![0.0; 8];
    s.read_box([40, 40, 6], [2, 2, 2], &mut out);
    assert_eq!(s.problem(), None);
    s.read_box([0, 0, 0], [2, 2, 2], &mut out);
    let problem = s.problem().expect("the corrupt chunk is reported");
    assert!(
        problem.contains("c.zarr") && problem.contains("level '0'"),
        "{problem}"
    );
    assert!(!problem.contains('\n'), "{problem}");
}

/// Four threads reading overlapping boxes of one stream at once, through a cache of
/// two chunks (every read evicts another thread's chunks): no deadlock, and every box
/// equals the whole read.
#[test]
fn concurrent_reads_through_a_small_cache_equal_the_whole_level() {
    let path = data("missing-chunk.zarr");
    let whole = open_volume(&path, &ReadOptions::default()).unwrap().volume;
    let chunk = Stream::open(&path, &ReadOptions::default(), 0, 1)
        .unwrap()
        .chunk_bytes();
    let s = Stream::open(&path, &ReadOptions::default(), 2 * chunk, 4).unwrap();
    let all = boxes(whole.dims);
    std::thread::scope(|scope| {
        for t in 0..4 {
            let (s, whole, all) = (&s, &whole, &all);
            scope.spawn(move || {
                for (lo, size) in all.iter().cycle().skip(t * 7).take(all.len()) {
                    let mut out = vec![f32::NAN; size.iter().product()];
                    s.read_box(*lo, *size, &mut out);
                    assert!(out == expected(whole, *lo, *size), "thread {t} box {lo:?}");
                }
            });
        }
    });
    assert!(s.cached_chunks() <= 2);
    assert_eq!(s.problem(), None);
}

/// A level of 2^32 voxels (no chunk written: every one missing), over the whole
/// read's limit of 2^31: the whole read refuses it, the stream opens it (it allocates
/// nothing by the level's size) and reads the fill value; its chunks are still checked
/// against `max_voxels`.
#[test]
fn a_streamed_level_may_exceed_the_whole_reads_voxel_limit() {
    let dir = tempfile::tempdir().unwrap();
    let store = edited_one_level_store(dir.path(), |array| {
        array["shape"] = serde_json::json!([1024, 2048, 2048]);
        array["chunk_grid"]["configuration"]["chunk_shape"] = serde_json::json!([64, 256, 256]);
        array["codecs"] =
            serde_json::json!([{"name": "bytes", "configuration": {"endian": "little"}}]);
    });
    let options = ReadOptions::default();
    let err = open_volume(&store, &options).unwrap_err();
    assert!(matches!(err, glint_io::IoError::TooLarge { .. }), "{err}");
    let s = Stream::open(&store, &options, 0, 1).unwrap();
    assert_eq!(s.dims(), [2048, 2048, 1024]);
    assert!(s
        .notes()
        .iter()
        .any(|n| n.contains("1024 of 1024 chunks missing")));
    let mut out = vec![f32::NAN; 8];
    s.read_box([2047, 2047, 1023], [2, 2, 2], &mut out);
    assert_eq!(out, vec![0.0; 8]);
    let small_chunks = ReadOptions {
        max_voxels: 1 << 20,
        ..ReadOptions::default()
    };
    let err = Stream::open(&store, &small_chunks, 0, 1).err().unwrap();
    assert!(err.to_string().contains("chunks of"), "{err}");
}
