//! The rules of an exhaustive check (`glint hw check`, `glint hw sweep`): how many
//! points a run may take, which ranges of `n` its report lists, and the full-scale
//! code of an output width (with `Design::with_out_bits` under the `tools` feature).
//! Front ends call these rather than restating them.

use crate::{Config, HwError, MAX_COS_BITS};

/// Largest exhaustive check one `glint hw check` runs (about a minute of CPU at
/// about 25 ns a point).
pub const MAX_CHECK_POINTS: u64 = 1 << 32;

/// Largest exhaustive check per step of `glint hw sweep` (it runs 30 to 40 of them).
pub const MAX_SWEEP_POINTS: u64 = 1 << 28;

/// Refuses a configuration whose exhaustive check (every cos code in [-1, 1] × every
/// `n`) exceeds `max` points, with the count and the largest `cos_bits` that fits at
/// its `n_bits` in the message. The count is exact (`u128`), so no width can wrap it
/// below the limit.
pub fn check_exhaustive_size(cfg: &Config, max: u64) -> Result<(), HwError> {
    let limit = u128::from(max);
    let fits = |c: &Config| c.exhaustive_points().is_some_and(|p| p <= limit);
    if fits(cfg) {
        return Ok(());
    }
    let points = cfg
        .exhaustive_points()
        .map_or_else(|| "too many".to_string(), |p| p.to_string());
    let hint = (2..=MAX_COS_BITS)
        .rev()
        .find(|&cos_bits| {
            fits(&Config {
                cos_bits,
                ..cfg.clone()
            })
        })
        .map_or_else(
            || "use a smaller n_bits".to_string(),
            |c| format!("at n_bits = {} use cos_bits <= {c}", cfg.n_bits),
        );
    Err(HwError::Unsupported(format!(
        "an exhaustive check of cos_bits = {} and n_bits = {} is {points} points per pass, \
         more than the {max} this command runs; {hint}",
        cfg.cos_bits, cfg.n_bits
    )))
}

/// The ranges of `n` a check reports for a unit whose largest `n` is `last`: 0-15,
/// 16-63, 64-255 and 256 up, those that start at or below `last` (the last one cut
/// at `last`), then all of `0..=last`.
pub fn check_ranges(last: u32) -> Vec<(u32, u32)> {
    let mut ranges = vec![(0u32, 15u32), (16, 63), (64, 255), (256, last)];
    ranges.retain(|&(a, _)| a <= last);
    if let Some(r) = ranges.last_mut() {
        r.1 = r.1.min(last);
    }
    ranges.push((0, last));
    ranges
}

/// `2^bits - 1`: the full-scale code of a `bits`-wide output, for any width (0 for
/// none, all ones from 64 up).
pub fn full_scale(bits: u32) -> u64 {
    u64::MAX
        .checked_shr(64u32.saturating_sub(bits))
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn oversized_exhaustive_checks_are_refused() {
        let cfg = |cos_bits, n_bits| Config {
            cos_bits,
            n_bits,
            ..Config::default()
        };
        // (2^29 + 1) · 2^10 > 2^32.
        assert!(check_exhaustive_size(&cfg(30, 10), MAX_CHECK_POINTS).is_err());
        assert!(check_exhaustive_size(&Config::default(), MAX_SWEEP_POINTS).is_ok());
        // (2^59 + 1) << 13 wraps to 8192 in u64: every cos_bits beyond the limit must
        // be refused at n_bits = 13: (2^(c-1) + 1) · 2^13 <= 2^32 only for c <= 19.
        for c in 2..=MAX_COS_BITS {
            let ok = check_exhaustive_size(&cfg(c, 13), MAX_CHECK_POINTS).is_ok();
            assert_eq!(ok, c <= 19, "cos_bits = {c}");
        }
        let e = check_exhaustive_size(&cfg(60, 13), MAX_CHECK_POINTS).unwrap_err();
        let msg = e.to_string();
        // (2^59 + 1) · 2^13, by hand.
        let points = ((1u128 << 59) + 1) * 8192;
        assert!(msg.contains(&points.to_string()), "{msg}");
        assert!(msg.contains("cos_bits <= 19"), "{msg}");
        assert!(!msg.contains('\n'), "{msg}");
    }

    #[test]
    fn check_ranges_cut_at_the_largest_n() {
        assert_eq!(
            check_ranges(1023),
            [(0, 15), (16, 63), (64, 255), (256, 1023), (0, 1023)]
        );
        assert_eq!(check_ranges(100), [(0, 15), (16, 63), (64, 100), (0, 100)]);
        assert_eq!(check_ranges(15), [(0, 15), (0, 15)]);
        assert_eq!(check_ranges(1), [(0, 1), (0, 1)]);
    }

    #[test]
    fn full_scale_by_hand() {
        assert_eq!(full_scale(0), 0);
        assert_eq!(full_scale(1), 1);
        assert_eq!(full_scale(8), 255);
        assert_eq!(full_scale(63), (1u64 << 63) - 1);
        assert_eq!(full_scale(64), u64::MAX);
        assert_eq!(full_scale(65), u64::MAX);
    }
}
