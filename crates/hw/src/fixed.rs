//! The one fixed-point primitive every stage uses: change the number of fraction bits.

use crate::Rounding;

/// Re-expresses the unsigned fixed-point value `x` (with `from` fraction bits) with `to`
/// fraction bits: exact when `to >= from` (a left shift), otherwise the low `from - to`
/// bits are dropped ([`Rounding::Truncate`]) or rounded to nearest with ties up
/// ([`Rounding::Nearest`], i.e. `floor(x / 2^k + 1/2)`).
///
/// Hardware equivalent: wiring (a shift) plus, for `Nearest`, an incrementer fed by the
/// highest dropped bit. The form `(x >> k) + bit(k-1)` cannot overflow, unlike
/// `(x + 2^(k-1)) >> k`.
#[inline(always)]
pub fn requantize(x: u128, from: u32, to: u32, mode: Rounding) -> u128 {
    if to >= from {
        x << (to - from)
    } else {
        let k = from - to;
        match mode {
            Rounding::Truncate => x >> k,
            Rounding::Nearest => (x >> k) + ((x >> (k - 1)) & 1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_by_hand() {
        // 0b1011 with 2 fraction bits = 2.75.
        assert_eq!(requantize(0b1011, 2, 0, Rounding::Truncate), 2);
        assert_eq!(requantize(0b1011, 2, 0, Rounding::Nearest), 3);
        // 2.5 ties up, 2.25 goes down.
        assert_eq!(requantize(0b1010, 2, 0, Rounding::Nearest), 3);
        assert_eq!(requantize(0b1001, 2, 0, Rounding::Nearest), 2);
        // Widening is exact.
        assert_eq!(requantize(3, 1, 4, Rounding::Truncate), 24);
        // No overflow at the top of the u128 range.
        assert_eq!(requantize(u128::MAX, 1, 0, Rounding::Nearest), 1u128 << 127);
    }
}
