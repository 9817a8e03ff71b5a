//! Named enums: every enum whose values users type (lobes, geometries, views, modes,
//! presets of a kind, ...) derives its names, its parser and its list with strum
//! (`EnumString`, `IntoStaticStr`, `Display`, `VariantNames`, `VariantArray`), so the
//! names `--help` lists, the parser and the messages cannot drift apart. [`Named`]
//! gives each its word in messages, and [`unknown`] the one message of a name that is
//! none of them.

/// A named enum and what it is called in messages.
pub trait Named: strum::VariantNames {
    /// The enum's word in messages (`lobe`, `view`, `sampling`, ...).
    const WHAT: &'static str;
}

/// The message for `name`, which is none of `T`'s names: `unknown view 'up': expected
/// one of anterior, posterior, ...`.
///
/// ```
/// use glint_lobe::{names::unknown, Geometry};
/// assert_eq!(unknown::<Geometry>("flat"), "unknown geometry 'flat': expected one of phong, blinn");
/// ```
pub fn unknown<T: Named>(name: &str) -> String {
    format!(
        "unknown {} '{name}': expected one of {}",
        T::WHAT,
        T::VARIANTS.join(", ")
    )
}
