//! The voxel-to-RAS affine from `space`, `space directions`, `space origin` or
//! `spacings`.

use std::path::Path;

use super::header::Fields;
use super::invalid;
use crate::common::{check_spacing, diagonal_affine};
use crate::IoError;

/// Parses "(x,y,z)" into three numbers; "none" gives `None`.
fn vector(path: &Path, s: &str) -> Result<Option<[f64; 3]>, IoError> {
    let s = s.trim();
    if s == "none" {
        return Ok(None);
    }
    let inner = s
        .strip_prefix('(')
        .and_then(|s| s.strip_suffix(')'))
        .ok_or_else(|| invalid(path, format!("'{s}' is not a vector like (1,0,0)")))?;
    let v: Vec<f64> = inner
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| invalid(path, format!("'{s}' is not a vector of numbers")))?;
    <[f64; 3]>::try_from(v)
        .map(Some)
        .map_err(|_| invalid(path, format!("'{s}' is not a 3-vector")))
}

/// Splits "(1,0,0) (0,1,0) none" into its items.
fn vectors(s: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = s.trim();
    while !rest.is_empty() {
        let end = if rest.starts_with('(') {
            rest.find(')').map_or(rest.len(), |i| i + 1)
        } else {
            rest.find(char::is_whitespace).unwrap_or(rest.len())
        };
        out.push(&rest[..end]);
        rest = rest[end..].trim_start();
    }
    out
}

/// The voxel-to-RAS affine and notes on where it came from: `space directions` and
/// `space origin`, or `spacings` (1 mm without them), converted from the header's
/// `space` to RAS.
pub(super) fn geometry(
    path: &Path,
    fields: &Fields,
    dimension: usize,
) -> Result<([[f64; 4]; 4], Vec<String>), IoError> {
    check_kinds(path, fields, dimension)?;
    let mut notes = Vec::new();
    let space = fields.get("space").map(str::to_ascii_lowercase);
    let flip = match space.as_deref() {
        Some("right-anterior-superior" | "ras") | None => [1.0, 1.0, 1.0],
        Some("left-posterior-superior" | "lps") => [-1.0, -1.0, 1.0],
        Some("left-anterior-superior" | "las") => [-1.0, 1.0, 1.0],
        Some(s) => {
            notes.push(format!("space '{s}' taken as RAS"));
            [1.0, 1.0, 1.0]
        }
    };
    let affine = if let Some(dirs) = fields.get("space directions") {
        let cols = direction_columns(path, dirs, dimension)?;
        let origin = space_origin(path, fields)?;
        let mut a = [[0.0; 4]; 4];
        for r in 0..3 {
            for c in 0..3 {
                a[r][c] = flip[r] * cols[c][r];
            }
            a[r][3] = flip[r] * origin[r];
        }
        a[3][3] = 1.0;
        notes.push(format!(
            "space {}",
            space.as_deref().unwrap_or("unspecified (taken as RAS)")
        ));
        a
    } else {
        let spacing = spacings(path, fields, &mut notes)?;
        // A space origin is a world position even without space directions.
        let origin = space_origin(path, fields)?;
        diagonal_affine(spacing, std::array::from_fn(|r| flip[r] * origin[r]))
    };
    Ok((affine, notes))
}

/// Every axis must be spatial: a color or vector axis (kinds RGB-color, vector, list,
/// ...) is not a voxel dimension.
fn check_kinds(path: &Path, fields: &Fields, dimension: usize) -> Result<(), IoError> {
    let Some(kinds) = fields.get("kinds") else {
        return Ok(());
    };
    for (i, k) in kinds.split_whitespace().take(dimension).enumerate() {
        if !matches!(
            k.to_ascii_lowercase().as_str(),
            "domain" | "space" | "none" | "???"
        ) {
            return Err(IoError::Unsupported {
                path: path.into(),
                what: format!(
                    "axis {i} is a non-spatial axis (kind '{k}'); only scalar volumes \
                     with spatial axes are read"
                ),
            });
        }
    }
    Ok(())
}

/// The `space directions`, one per axis, in the header's space; a 2D image gets a
/// unit third axis along its plane's normal.
fn direction_columns(path: &Path, dirs: &str, dimension: usize) -> Result<[[f64; 3]; 3], IoError> {
    let items = vectors(dirs);
    if items.len() != dimension {
        return Err(invalid(
            path,
            format!("{} space directions for dimension {dimension}", items.len()),
        ));
    }
    let mut cols = [[0.0; 3]; 3];
    for (col, item) in cols.iter_mut().zip(items) {
        *col = vector(path, item)?.ok_or_else(|| IoError::Unsupported {
            path: path.into(),
            what: "a non-spatial axis ('none' direction)".into(),
        })?;
    }
    if dimension == 2 {
        cols[2] = unit_normal(cols[0], cols[1]);
    }
    Ok(cols)
}

/// `a` x `b` scaled to unit length (left at zero when `a` and `b` are parallel).
fn unit_normal(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let n = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if l > 0.0 {
        n.map(|x| x / l)
    } else {
        n
    }
}

/// The `space origin`, zero when absent or `none`.
fn space_origin(path: &Path, fields: &Fields) -> Result<[f64; 3], IoError> {
    match fields.get("space origin") {
        Some(o) => Ok(vector(path, o)?.unwrap_or([0.0; 3])),
        None => Ok([0.0; 3]),
    }
}

/// The voxel size from `spacings` (checked finite and positive), 1 mm when absent (with
/// a note).
fn spacings(path: &Path, fields: &Fields, notes: &mut Vec<String>) -> Result<[f64; 3], IoError> {
    let mut spacing = [1.0; 3];
    match fields.get("spacings") {
        Some(s) => {
            for (i, t) in s.split_whitespace().take(3).enumerate() {
                spacing[i] = t.parse::<f64>().unwrap_or(f64::NAN);
            }
            check_spacing(path, spacing)?;
        }
        None => notes.push("no spacings or space directions: 1 mm voxels".into()),
    }
    Ok(spacing)
}

#[cfg(test)]
mod tests {
    use super::vectors;

    #[test]
    fn splits_space_directions() {
        assert_eq!(
            vectors("(1,0,0) (0, 1,0)  none (0,0,1.5)"),
            vec!["(1,0,0)", "(0, 1,0)", "none", "(0,0,1.5)"]
        );
    }
}
