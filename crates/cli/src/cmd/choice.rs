//! Option values chosen from a closed set, listed by `--help`.

use std::fmt::Display;
use std::str::FromStr;

use clap::builder::{PossibleValuesParser, TypedValueParser};

/// A clap value parser for a library enum that has names (`FromStr`) but no clap
/// derive (the libraries do not depend on clap): `--help` lists `names`, and the value
/// is parsed by the type itself, so the names and the parser cannot drift apart.
pub fn choice<T>(names: impl IntoIterator<Item = &'static str>) -> impl TypedValueParser<Value = T>
where
    T: FromStr + Clone + Send + Sync + 'static,
    T::Err: Display,
{
    PossibleValuesParser::new(names).try_map(|s| s.parse::<T>().map_err(|e| e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;
    use glint_lobe::LobeKind;

    #[derive(Parser)]
    struct Cli {
        #[arg(long, value_parser = choice::<LobeKind>(LobeKind::NAMES.iter().copied()))]
        lobe: LobeKind,
    }

    #[test]
    fn names_parse_and_others_are_refused_with_the_list() {
        let cli = Cli::try_parse_from(["x", "--lobe", "minimax"]).unwrap();
        assert_eq!(cli.lobe, LobeKind::Minimax);
        let err = Cli::try_parse_from(["x", "--lobe", "cosine"])
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("cosine") && err.contains("schlick"), "{err}");
    }
}
