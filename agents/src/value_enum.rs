//! The command line's value lists come from the types: [`clap_value_enum!`](crate::clap_value_enum)
//! implements `clap::ValueEnum` for an enum with `ALL` (every value, in the help's order) and
//! `name()` (its spelling on the command line), in every crate of the workspace.

/// Implements `clap::ValueEnum` for `$ty` from `<$ty>::ALL` and `<$ty>::name`; the calling
/// crate needs `clap` (invoke it under its `clap` feature).
#[macro_export]
macro_rules! clap_value_enum {
    ($ty:ty) => {
        impl clap::ValueEnum for $ty {
            fn value_variants<'a>() -> &'a [Self] {
                &Self::ALL
            }

            fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
                Some(clap::builder::PossibleValue::new(self.name()))
            }
        }
    };
}
