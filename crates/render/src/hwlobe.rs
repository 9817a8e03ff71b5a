//! The `hw` lobe: the specular value of glint-hw's bit-accurate unit, tabulated over
//! its cosine codes once per (configuration, n) (`glint_hw::Unit::cos_table`) and
//! looked up per sample. [`HwCache`] keeps the last unit and table, so a
//! [`Renderer`](crate::Renderer) rendering frame after frame (a viewer, a notebook)
//! builds neither again while the configuration and n stay the same.

use std::sync::{Arc, Mutex, PoisonError};

use glint_hw::{Config, Unit};
use glint_lobe::CosTable;

use glint_core::RenderError;

/// The last unit built and its last table.
#[derive(Clone)]
struct Entry {
    config: Config,
    /// Built once per configuration: a minimax ROM searches a coefficient per n.
    unit: Arc<Unit>,
    /// The table for one `n` input code.
    table: Option<(u32, Arc<CosTable>)>,
}

/// The last hardware unit and cosine table, shared by every resolve of a renderer.
#[derive(Default)]
pub(crate) struct HwCache {
    last: Mutex<Option<Entry>>,
}

impl Clone for HwCache {
    /// A cache holding the same unit and table (shared): a renderer cloned for another
    /// viewer client starts from the last table.
    fn clone(&self) -> Self {
        let last = self
            .last
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone();
        HwCache {
            last: Mutex::new(last),
        }
    }
}

impl HwCache {
    /// The table of `config`'s unit for shininess `n` (rounded to the unit's integer
    /// input, [`Unit::n_code`]): the cached one when the configuration and the code
    /// are the last ones asked for, else a new one (which replaces it).
    pub(crate) fn table(&self, config: &Config, n: f64) -> Result<Arc<CosTable>, RenderError> {
        // A panic while building cannot leave a half-written entry (entries are
        // replaced whole), so a poisoned lock is still consistent.
        let mut last = self.last.lock().unwrap_or_else(PoisonError::into_inner);
        let entry = match last.take() {
            Some(e) if e.config == *config => e,
            _ => Entry {
                config: config.clone(),
                unit: Arc::new(
                    Unit::new(config.clone()).map_err(|e| RenderError::HwConfig(Box::new(e)))?,
                ),
                table: None,
            },
        };
        let entry = last.insert(entry);
        let code = entry.unit.n_code(n).map_err(|source| RenderError::HwN {
            n,
            source: Box::new(source),
        })?;
        if let Some((c, table)) = &entry.table {
            if *c == code {
                return Ok(table.clone());
            }
        }
        let table = Arc::new(
            entry
                .unit
                .cos_table(code)
                .map_err(|e| RenderError::HwTable(Box::new(e)))?,
        );
        entry.table = Some((code, table.clone()));
        Ok(table)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_unit_and_n_reuse_the_table_and_others_rebuild_it() {
        let cache = HwCache::default();
        let config = Config::default();
        let a = cache.table(&config, 40.0).unwrap();
        // 40.2 is the same integer input.
        assert!(Arc::ptr_eq(&a, &cache.table(&config, 40.2).unwrap()));
        let b = cache.table(&config, 41.0).unwrap();
        assert!(!Arc::ptr_eq(&a, &b));
        assert_ne!(*a, *b, "n = 40 and 41 give different tables");
        let wide = Config {
            out_bits: 12,
            ..Config::default()
        };
        let c = cache.table(&wide, 41.0).unwrap();
        assert_ne!(*b, *c, "8- and 12-bit outputs give different tables");
        // The table is the unit's, built independently.
        let unit = Unit::new(wide).unwrap();
        assert_eq!(*c, unit.cos_table(41).unwrap());
    }

    #[test]
    fn bad_configurations_and_n_are_typed_errors_that_keep_their_source() {
        use std::error::Error;
        let cache = HwCache::default();
        let bad = Config {
            v: 11,
            ..Config::default()
        };
        let err = cache.table(&bad, 10.0).unwrap_err();
        assert!(matches!(err, RenderError::HwConfig(_)), "{err:?}");
        assert!(err.source().unwrap().to_string().contains("v = 11"));
        let err = cache.table(&Config::default(), 5000.0).unwrap_err();
        assert!(matches!(err, RenderError::HwN { .. }), "{err:?}");
        assert!(err.source().unwrap().to_string().contains("1023"), "{err}");
        // A failure leaves the cache usable.
        assert!(cache.table(&Config::default(), 10.0).is_ok());
    }
}
