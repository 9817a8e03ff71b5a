//! A field past the adapter's 3D texture side, paged: its voxels cut into cubic pages
//! of side `B`, the pages laid out in an atlas texture within the limit, and a page
//! table (a storage buffer) giving each page's slot in the atlas. The shader's every
//! voxel read (`texel` in `local.wgsl`) goes through the table, so the atlas needs no
//! border voxels and the values read are the field's own, bit for bit. Pages whose
//! voxels all hold one value with zero gradients (the air of many MR and CT volumes)
//! share one slot per value, which is where a paged field takes less memory than a
//! plain one.

use std::collections::HashMap;

use crate::adapter::GpuError;

/// Words before the page table's slots: `B`, the pages along x and y, the atlas's
/// slots along x and y, and padding.
pub(crate) const HEADER: usize = 8;

/// The page sides tried, largest first (fewer table reads per page crossed).
const SIDES: [usize; 3] = [32, 16, 8];

/// How a field of `dims` is paged into an atlas within a 3D texture side of `limit`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Layout {
    /// The page side, voxels.
    pub(crate) side: usize,
    /// The pages along each axis.
    pub(crate) pages: [usize; 3],
    /// The atlas's slots along each axis (its dims are `side` times these).
    pub(crate) slots: [usize; 3],
}

/// Whether `dims` need paging under `limit` (a side past it), and its layout: the
/// largest page side whose atlas holds every page within the limit (before sharing
/// constant pages, so the layout does not depend on the values). An error when no
/// page side fits: the volume has more voxels than a `limit`-sided atlas.
pub(crate) fn layout(dims: [usize; 3], limit: usize) -> Result<Option<Layout>, GpuError> {
    if dims.iter().all(|&n| n <= limit) {
        return Ok(None);
    }
    for side in SIDES {
        let per = limit / side;
        if per == 0 {
            continue;
        }
        let pages = dims.map(|n| n.div_ceil(side));
        let total: usize = pages.iter().product();
        let x = total.min(per);
        let y = total.div_ceil(x).min(per);
        let z = total.div_ceil(x * y);
        if z <= per {
            return Ok(Some(Layout {
                side,
                pages,
                slots: [x, y, z],
            }));
        }
    }
    Err(GpuError::Unsupported(format!(
        "a volume of {}x{}x{} voxels does not fit an atlas within the adapter's 3D texture side of {limit}, even paged",
        dims[0], dims[1], dims[2]
    )))
}

/// A paged field on the host, ready to upload: the atlas's values and gradients
/// (slot after slot, each `side`^3 voxels, x fastest) and the page table.
pub(crate) struct Paged {
    /// The atlas's slots in use (at most the layout's).
    pub(crate) used: usize,
    /// Per used slot, its `side`^3 values.
    pub(crate) values: Vec<f32>,
    /// Per used slot, its `side`^3 gradients (the field's brick integers).
    pub(crate) gradients: Vec<[i16; 4]>,
    /// The table: [`HEADER`] words, then each page's slot (x fastest).
    pub(crate) table: Vec<u32>,
}

/// The pages of a field of `dims` (`values` and `gradients`, x fastest) in `layout`:
/// each page's voxels copied into a slot of its own, except that pages holding one
/// value throughout with zero gradients share a slot per value. Voxels of a page past
/// the volume's end repeat nothing: they are never read (the shader clamps reads to
/// the volume) and are left 0.
pub(crate) fn pages(
    dims: [usize; 3],
    (values, gradients): (&[f32], &[[i16; 4]]),
    layout: &Layout,
) -> Paged {
    let b = layout.side;
    let [px, py, pz] = layout.pages;
    let voxels = b * b * b;
    let mut table = vec![0u32; HEADER + px * py * pz];
    table[..5].copy_from_slice(&[b, px, py, layout.slots[0], layout.slots[1]].map(|x| x as u32));
    let mut out_values: Vec<f32> = Vec::new();
    let mut out_gradients: Vec<[i16; 4]> = Vec::new();
    let mut constant: HashMap<u32, u32> = HashMap::new();
    let mut v = vec![0.0f32; voxels];
    let mut g = vec![[0i16; 4]; voxels];
    for (p, slot) in table[HEADER..].iter_mut().enumerate() {
        let page = [p % px, (p / px) % py, p / (px * py)];
        gather(dims, (values, gradients), (page, b), (&mut v, &mut g));
        let first = v[0];
        let flat =
            v.iter().all(|x| x.to_bits() == first.to_bits()) && g.iter().all(|&x| x == [0; 4]);
        let next = (out_values.len() / voxels) as u32;
        if flat {
            if let Some(&s) = constant.get(&first.to_bits()) {
                *slot = s;
                continue;
            }
            constant.insert(first.to_bits(), next);
        }
        *slot = next;
        out_values.extend_from_slice(&v);
        out_gradients.extend_from_slice(&g);
    }
    Paged {
        used: out_values.len() / voxels,
        values: out_values,
        gradients: out_gradients,
        table,
    }
}

/// Copies page `page` (side `b`) of the field into `v` and `g`, the voxels past the
/// volume set to the page's first voxel (so a page at the volume's edge can still be
/// constant).
fn gather(
    dims: [usize; 3],
    (values, gradients): (&[f32], &[[i16; 4]]),
    (page, b): ([usize; 3], usize),
    (v, g): (&mut [f32], &mut [[i16; 4]]),
) {
    let [nx, ny, nz] = dims;
    let lo = page.map(|p| p * b);
    let inside = |z: usize, y: usize, x: usize| lo[0] + x < nx && lo[1] + y < ny && lo[2] + z < nz;
    let at = |z: usize, y: usize, x: usize| lo[0] + x + nx * (lo[1] + y + ny * (lo[2] + z));
    let first = at(0, 0, 0);
    for z in 0..b {
        for y in 0..b {
            for x in 0..b {
                let i = if inside(z, y, x) { at(z, y, x) } else { first };
                let o = x + b * (y + b * z);
                v[o] = values[i];
                g[o] = gradients[i];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_volume_within_the_limit_is_not_paged_and_one_past_any_atlas_is_refused() {
        assert_eq!(layout([64, 64, 64], 64).unwrap(), None);
        // 24 x 24 x 96 under 48: pages of 16, 2 x 2 x 6 = 24 of them in 3 x 3 x 3 slots.
        let l = layout([24, 24, 96], 48).unwrap().unwrap();
        assert_eq!(l.side, 16);
        assert_eq!(l.pages, [2, 2, 6]);
        assert_eq!(l.slots, [3, 3, 3]);
        // A long thin volume takes the largest pages: 4097 x 2 x 2 under 4096.
        let l = layout([4097, 2, 2], 4096).unwrap().unwrap();
        assert_eq!((l.side, l.pages, l.slots), (32, [129, 1, 1], [128, 2, 1]));
        // 48^3 under 32: more voxels than a 32^3 atlas holds.
        let e = layout([48, 48, 48], 32).unwrap_err().to_string();
        assert!(e.contains("48x48x48") && e.contains("32"), "{e}");
    }

    #[test]
    fn every_voxel_reads_back_through_the_table_and_constant_pages_share_a_slot() {
        let dims = [12, 9, 35];
        let n: usize = dims.iter().product();
        // Zero (flat) below z = 16, values above: the flat pages share one slot.
        let values: Vec<f32> = (0..n)
            .map(|i| {
                if i / (12 * 9) < 16 {
                    0.0
                } else {
                    i as f32 * 0.5
                }
            })
            .collect();
        let gradients: Vec<[i16; 4]> = (0..n)
            .map(|i| {
                if i / (12 * 9) < 16 {
                    [0; 4]
                } else {
                    [i as i16, 1, 2, 0]
                }
            })
            .collect();
        let l = layout(dims, 24).unwrap().unwrap();
        assert_eq!(l.side, 8);
        let p = pages(dims, (&values, &gradients), &l);
        let b = l.side;
        let [px, py, _] = l.pages;
        // 2 x 2 x 5 pages; the 8 below z = 16 are flat zero: one slot for them.
        assert_eq!(p.used, 20 - 8 + 1);
        for (i, (&want_v, &want_g)) in values.iter().zip(&gradients).enumerate() {
            let c = [i % 12, (i / 12) % 9, i / 108];
            let page = c.map(|x| x / b);
            let slot = p.table[HEADER + page[0] + px * (page[1] + py * page[2])] as usize;
            let o = c.map(|x| x % b);
            let at = slot * b * b * b + o[0] + b * (o[1] + b * o[2]);
            assert_eq!(p.values[at].to_bits(), want_v.to_bits(), "value at {c:?}");
            assert_eq!(p.gradients[at], want_g, "gradient at {c:?}");
        }
    }
}
