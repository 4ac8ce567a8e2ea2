//! "paper 003" in any text as a link to that paper in the home page's reference list
//! (`#/home/paper-003`; the home page scrolls to the sub-path's entry).

use leptos::prelude::*;

use crate::web::route::Page;

/// The papers the lab numbers: "000" … "004".
const PAPER_COUNT: u32 = 5;

/// A piece of text: plain, or a mention of a paper with its three-digit number.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Piece<'a> {
    Text(&'a str),
    Paper { shown: &'a str, number: &'a str },
}

/// `text` cut at each "paper 00x" / "Paper 00x" (x a paper the lab has).
fn pieces(text: &str) -> Vec<Piece<'_>> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(at) = find_mention(rest) {
        if at > 0 {
            out.push(Piece::Text(&rest[..at]));
        }
        let shown = &rest[at..at + "paper 000".len()];
        out.push(Piece::Paper {
            shown,
            number: &shown["paper ".len()..],
        });
        rest = &rest[at + shown.len()..];
    }
    if !rest.is_empty() {
        out.push(Piece::Text(rest));
    }
    out
}

/// Where the first mention in `text` starts, if any.
fn find_mention(text: &str) -> Option<usize> {
    text.match_indices("aper ").find_map(|(i, _)| {
        let start = i.checked_sub(1)?;
        // `get`: the byte before may be inside a wider character ("×aper").
        let head = text.get(start..i)?;
        let digits = text.get(i + "aper ".len()..i + "aper ".len() + 3)?;
        let known = digits.bytes().all(|b| b.is_ascii_digit())
            && digits.parse::<u32>().is_ok_and(|n| n < PAPER_COUNT);
        let word_ends = text[i + "aper ".len() + 3..]
            .chars()
            .next()
            .is_none_or(|c| !c.is_ascii_alphanumeric());
        let word_starts = text[..start]
            .chars()
            .next_back()
            .is_none_or(|c| !c.is_alphanumeric());
        (matches!(head, "p" | "P") && known && word_starts && word_ends).then_some(start)
    })
}

/// The link to paper `number` ("003") in the home page's list.
pub fn paper_href(number: &str) -> String {
    format!("{}/paper-{number}", Page::Home.href())
}

/// `text` with each paper it mentions a link to the reference list.
#[component]
pub fn WithPaperLinks(#[prop(into)] text: String) -> impl IntoView {
    pieces(&text)
        .into_iter()
        .map(|piece| match piece {
            Piece::Text(t) => t.to_string().into_any(),
            Piece::Paper { shown, number } => {
                view! { <a href=paper_href(number)>{shown.to_string()}</a> }.into_any()
            }
        })
        .collect_view()
}

#[cfg(test)]
mod tests {
    use super::{pieces, Piece};

    #[test]
    fn each_paper_mention_is_cut_out_with_its_number() {
        assert_eq!(
            pieces("as in paper 003 (Kim), and Paper 000's bench"),
            vec![
                Piece::Text("as in "),
                Piece::Paper {
                    shown: "paper 003",
                    number: "003"
                },
                Piece::Text(" (Kim), and "),
                Piece::Paper {
                    shown: "Paper 000",
                    number: "000"
                },
                Piece::Text("'s bench"),
            ]
        );
    }

    #[test]
    fn other_numbers_and_words_stay_text() {
        for text in [
            "paper 005",
            "paper 0031",
            "newspaper 001",
            "papers 001",
            "paper 00",
        ] {
            assert_eq!(pieces(text), vec![Piece::Text(text)], "{text}");
        }
        assert_eq!(pieces(""), vec![]);
    }
}
