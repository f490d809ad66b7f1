//! Flags for the library's named options ([`raypipe::Choice`]): their names and help come from the
//! library's lists, so a new mode needs no change here.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use raypipe::Choice;

/// A clap value parser for any [`Choice`].
pub fn choice<T: Choice + Send + Sync + Clone>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(T::ALL.iter().map(|v| PossibleValue::new(v.name()).help(v.about())))
        .map(|name| T::from_name(&name).expect("clap offered only these names"))
}
