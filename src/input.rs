//! Numbers typed by a person, parsed leniently where that is safe and strictly where it is not.
//!
//! The browser forms keep what the user typed and parse it with these; an `Err` is the message
//! shown beside the field.
//!
//! [`table`] describes settings as rows of a table (name, unit, range, default) that a form and
//! the command line parse alike.
//!
//! | file | what |
//! |---|---|
//! | [`table`] | tables of settings: each setting a page or the command line accepts is a row |

pub mod table;

/// Parses a decimal number typed by a person: surrounding space is ignored and a decimal comma is
/// accepted, since many of our users' locales write `2,5`; a comma that could as well be a
/// thousands separator (`1,500`) is refused with a message rather than guessed.
///
/// ```
/// assert_eq!(cutlab::input::parse_number(" 2,5 "), Ok(2.5));
/// assert!(cutlab::input::parse_number("inf").is_err());
/// ```
pub fn parse_number(text: &str) -> Result<f64, String> {
    let typed = text.trim();
    if let Some((whole, fraction)) = typed.split_once(',') {
        // "1,500" is 1.5 in a decimal-comma locale and 1500 with a thousands separator: a guess
        // either way could run a feed a thousand times off, so ask. "0,125" is unambiguous.
        let looks_like_thousands = fraction.len() == 3
            && fraction.bytes().all(|b| b.is_ascii_digit())
            && !whole
                .trim_start_matches(['-', '+'])
                .trim_start_matches('0')
                .is_empty();
        if looks_like_thousands {
            return Err(format!(
                "\"{typed}\" is ambiguous: write it without a thousands separator, or with a decimal point"
            ));
        }
    }
    let cleaned = typed.replace(',', ".");
    if cleaned.is_empty() {
        return Err("enter a number".to_string());
    }
    match cleaned.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("\"{}\" is not a number", text.trim())),
    }
}

/// Parses a whole number typed by a person.
///
/// ```
/// assert_eq!(cutlab::input::parse_count("10"), Ok(10));
/// assert!(cutlab::input::parse_count("2.5").is_err());
/// ```
pub fn parse_count(text: &str) -> Result<usize, String> {
    parse_whole(text, "")
}

/// Parses a simulation seed: any whole number from 0 to 2⁶⁴ − 1, the same range natively and in
/// the browser (where `usize` is 32 bits).
///
/// ```
/// assert_eq!(cutlab::input::parse_seed("18446744073709551615"), Ok(u64::MAX));
/// assert!(cutlab::input::parse_seed("-1").is_err());
/// ```
pub fn parse_seed(text: &str) -> Result<u64, String> {
    parse_whole(text, " from 0 to 18446744073709551615")
}

/// A whole number of type `T`; `range` (e.g. " from 0 to 9") completes the error message.
fn parse_whole<T: std::str::FromStr>(text: &str, range: &str) -> Result<T, String> {
    let cleaned = text.trim();
    if cleaned.is_empty() {
        return Err("enter a whole number".to_string());
    }
    cleaned
        .parse::<T>()
        .map_err(|_| format!("\"{cleaned}\" is not a whole number{range}"))
}

/// A name a person typed, as a file name's stem: ASCII letters and digits in lower case, every
/// run of anything else one hyphen, none at either end ("Cutting force" → "cutting-force").
///
/// ```
/// use cutlab::input::file_slug;
/// assert_eq!(file_slug("Cutting force"), "cutting-force");
/// assert_eq!(file_slug("  Run #3 (mill, 80 %) "), "run-3-mill-80");
/// assert_eq!(file_slug("Ölfilm"), "lfilm");
/// ```
pub fn file_slug(text: &str) -> String {
    let mut slug = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_ascii_alphanumeric() {
            slug.push(c.to_ascii_lowercase());
        } else if !slug.is_empty() && !slug.ends_with('-') {
            slug.push('-');
        }
    }
    slug.trim_end_matches('-').to_string()
}

/// `v` to three significant digits, as a table or a result line shows a measured or computed
/// value (its meaning, not the float's noise): 0.439, 1.38, 116, 12300; an exponent below 0.001
/// or from a million up.
///
/// ```
/// use cutlab::input::three_significant;
/// assert_eq!(three_significant(0.4389), "0.439");
/// assert_eq!(three_significant(1.379), "1.38");
/// assert_eq!(three_significant(115.7403), "116");
/// assert_eq!(three_significant(12_345.0), "12300");
/// assert_eq!(three_significant(10.0), "10");
/// assert_eq!(three_significant(-0.06917), "-0.0692");
/// assert_eq!(three_significant(0.0), "0");
/// assert_eq!(three_significant(2.5e-5), "2.5e-5");
/// assert_eq!(three_significant(f64::NAN), "NaN");
/// ```
pub fn three_significant(v: f64) -> String {
    significant(v, 3)
}

/// `v` to `digits` significant digits (1 to 15), trailing zeros dropped; an exponent below 0.001
/// or from a million up. [`three_significant`] is the tables' and result lines' precision; a
/// lesson's check shows four, so that a value beside its threshold reads apart from it.
///
/// ```
/// use cutlab::input::significant;
/// assert_eq!(significant(3.214_59, 4), "3.215");
/// assert_eq!(significant(1234.6, 4), "1235");
/// assert_eq!(significant(12_345.6, 4), "12350");
/// assert_eq!(significant(0.05, 4), "0.05");
/// assert_eq!(significant(2.5e-5, 4), "2.5e-5");
/// assert_eq!(significant(1.234_56e7, 2), "1.2e7");
/// ```
pub fn significant(v: f64, digits: u32) -> String {
    if v == 0.0 || !v.is_finite() {
        return readable(v);
    }
    let digits = digits.clamp(1, 15) as i32;
    let magnitude = v.abs();
    if !(1e-3..1e6).contains(&magnitude) {
        let decimals = (digits - 1) as usize;
        let text = format!("{v:.decimals$e}");
        return match text.split_once('e') {
            Some((mantissa, exponent)) => format!(
                "{}e{exponent}",
                mantissa.trim_end_matches('0').trim_end_matches('.')
            ),
            None => text,
        };
    }
    // Digits before the point, less one: 0 for 1.38, 2 for 116, -1 for 0.439.
    let order = magnitude.log10().floor() as i32;
    if order >= digits - 1 {
        let unit = 10f64.powi(order - (digits - 1));
        format!("{:.0}", (v / unit).round() * unit)
    } else {
        let decimals = (digits - 1 - order) as usize;
        let text = format!("{v:.decimals$}");
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// `v` as a person reads it in a message: plain digits with at most four decimals, or an exponent
/// with at most five significant digits when very large or small — 1e300, not a 301-digit
/// integer; 1e-300, not "0.0000"; 3.4028e38, not 3.4028234663852886e38. Every number a message
/// shows goes through here.
///
/// ```
/// use cutlab::input::readable;
/// assert_eq!(readable(1e308), "1e308");
/// assert_eq!(readable(1e300), "1e300");
/// assert_eq!(readable(-1e-300), "-1e-300");
/// assert_eq!(readable(f64::from(f32::MAX)), "3.4028e38");
/// assert_eq!(readable(20000.0), "20000");
/// assert_eq!(readable(0.125), "0.125");
/// assert_eq!(readable(2e-9), "2e-9");
/// assert_eq!(readable(f64::NAN), "NaN");
/// assert_eq!(readable(f64::NEG_INFINITY), "-inf");
/// ```
pub fn readable(v: f64) -> String {
    if v == 0.0 || (1e-3..1e7).contains(&v.abs()) {
        let rounded = format!("{v:.4}");
        rounded
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    } else if v.is_finite() {
        let rounded = format!("{v:.4e}");
        match rounded.split_once('e') {
            Some((mantissa, exponent)) => format!(
                "{}e{exponent}",
                mantissa.trim_end_matches('0').trim_end_matches('.')
            ),
            None => rounded,
        }
    } else {
        format!("{v}")
    }
}

/// Text from the user's input in a message: quoted, and cut after 40 characters with its length
/// said, so a 10 MB field makes a one-line message, not a 10 MB one.
///
/// ```
/// use cutlab::input::excerpt;
/// assert_eq!(excerpt("abc"), "\"abc\"");
/// assert_eq!(excerpt(&"x".repeat(1000)), format!("\"{}\"… (1000 characters)", "x".repeat(40)));
/// ```
pub fn excerpt(text: &str) -> String {
    const SHOWN: usize = 40;
    match text.char_indices().nth(SHOWN) {
        None => format!("{text:?}"),
        Some((at, _)) => format!("{:?}… ({} characters)", &text[..at], text.chars().count()),
    }
}

/// A message that may quote the user's input at length (a parser's `unknown field \`…\``) cut to
/// one short line: at most 300 characters, its start and its end kept (where a parser says the
/// line and column), the cut said.
///
/// ```
/// use cutlab::input::one_short_line;
/// assert_eq!(one_short_line("line 3: bad"), "line 3: bad");
/// let long = format!("unknown field `{}` at line 1 column 9", "x".repeat(10_000));
/// let short = one_short_line(&long);
/// assert!(short.len() < 320 && short.ends_with("at line 1 column 9"), "{short}");
/// ```
pub fn one_short_line(message: &str) -> String {
    const KEPT: usize = 140;
    let message = message.replace(['\n', '\r'], " ");
    let count = message.chars().count();
    if count <= 2 * KEPT + 20 {
        return message;
    }
    let head: String = message.chars().take(KEPT).collect();
    let tail: String = message.chars().skip(count - KEPT).collect();
    format!("{head}… ({} characters cut) …{tail}", count - 2 * KEPT)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_accept_decimal_commas_and_reject_garbage() {
        assert_eq!(parse_number(" 2,5 "), Ok(2.5));
        assert_eq!(parse_number("1e3"), Ok(1000.0));
        assert_eq!(parse_number(""), Err("enter a number".to_string()));
        assert_eq!(
            parse_number("abc"),
            Err("\"abc\" is not a number".to_string())
        );
        assert!(parse_number("inf").is_err());
        assert_eq!(parse_number("0,125"), Ok(0.125));
        assert_eq!(parse_number("1,25"), Ok(1.25));
        assert!(parse_number("1,500").unwrap_err().contains("ambiguous"));
        assert!(parse_number("-2,000").unwrap_err().contains("ambiguous"));
        assert!(parse_number("1,000,000").is_err());
        assert_eq!(parse_count("10"), Ok(10));
        assert!(parse_count("-1").is_err());
        assert!(parse_count("2.5").is_err());
    }
}
