//! Numbers typed by a person, parsed leniently where that is safe and strictly where it is not.
//!
//! The browser forms keep what the user typed and parse it with these; an `Err` is the message
//! shown beside the field.

/// Parses a decimal number typed by a person: surrounding space is ignored and a decimal comma is
/// accepted, since many of our users' locales write `2,5`.
///
/// ```
/// assert_eq!(cutlab::input::parse_number(" 2,5 "), Ok(2.5));
/// assert!(cutlab::input::parse_number("inf").is_err());
/// ```
pub fn parse_number(text: &str) -> Result<f64, String> {
    let cleaned = text.trim().replace(',', ".");
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
    let cleaned = text.trim();
    if cleaned.is_empty() {
        return Err("enter a whole number".to_string());
    }
    cleaned
        .parse::<usize>()
        .map_err(|_| format!("\"{cleaned}\" is not a whole number"))
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
        assert_eq!(parse_count("10"), Ok(10));
        assert!(parse_count("-1").is_err());
        assert!(parse_count("2.5").is_err());
    }
}
