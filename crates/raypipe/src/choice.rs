//! Enums a user picks by name: `--accel stack` on the command line, `as = "spheres"` in a scene file,
//! `?accel=stack` in a web page. Each lists its variants in `ALL`, so that tests, benchmarks and
//! menus go through every mode without retyping the list.

/// A closed set of named options.
pub trait Choice: Copy + PartialEq + std::fmt::Debug + 'static {
    /// Every variant, in the order menus and benchmarks show them.
    const ALL: &'static [Self];
    /// The name users type.
    fn name(self) -> &'static str;
    /// One line on what it does, for help texts and menus.
    fn about(self) -> &'static str;
    /// The choice that `name` names (its command-line and URL spelling), if one does.
    fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|v| v.name() == name)
    }
    /// The names, for messages: "brute, stack, stackless, threaded, wide".
    fn names() -> String {
        Self::ALL.iter().map(|v| v.name()).collect::<Vec<_>>().join(", ")
    }
}

/// Implements [`Choice`] and `Display` (the name) for an enum from `(Variant, "name", "about")` rows.
/// Exported from here as [`impl_choice`]; `macro_export` alone would put it at the crate root.
#[doc(hidden)]
#[macro_export]
macro_rules! __impl_choice {
    ($ty:ty, [$(($variant:ident, $name:literal, $about:literal)),+ $(,)?]) => {
        impl $crate::choice::Choice for $ty {
            const ALL: &'static [Self] = &[$(<$ty>::$variant),+];
            fn name(self) -> &'static str {
                match self { $(<$ty>::$variant => $name),+ }
            }
            fn about(self) -> &'static str {
                match self { $(<$ty>::$variant => $about),+ }
            }
        }
        impl std::fmt::Display for $ty {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str($crate::choice::Choice::name(*self))
            }
        }
    };
}

#[doc(inline)]
pub use crate::__impl_choice as impl_choice;
