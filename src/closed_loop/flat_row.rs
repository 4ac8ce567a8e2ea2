//! A row of numbers as it travels to and from a computation worker: one flat list of `f64`, in
//! an order written once (the `flat_row!` macro), for the trace rows ([`super::transfer`]) and the
//! recordings' blocks ([`super::recording_jobs`]).

/// A row of numbers and flags as it travels between a worker and the page: one flat list of
/// `f64`, its numbers, then its flags as 0 or 1, in the order the invocation lists them once.
/// Gives the count per row (with the doc given), a function from a row to its values and one back
/// (a missing value reads as NaN, a flag is set when not 0); both take every field of the row by
/// name, so a field added to the row fails to compile until it travels.
macro_rules! flat_row {
    (
        $row:ident;
        $(#[$count_doc:meta])* $count:ident,
        $values:ident,
        $from:ident;
        numbers: $($number:ident),+ $(,)?
        $(; flags: $($flag:ident),+ $(,)?)?
    ) => {
        $(#[$count_doc])*
        pub const $count: usize = [$(stringify!($number),)+ $($(stringify!($flag),)+)?].len();

        fn $values(row: &$row) -> [f64; $count] {
            let $row { $($number,)+ $($($flag,)+)? } = *row;
            [$($number,)+ $($(if $flag { 1.0 } else { 0.0 },)+)?]
        }

        fn $from(v: &[f64]) -> $row {
            let mut values = v.iter().copied();
            let mut next = || values.next().unwrap_or(f64::NAN);
            // A struct's fields are evaluated in the order written.
            $row { $($number: next(),)+ $($($flag: next() != 0.0,)+)? }
        }
    };
}
pub(crate) use flat_row;
