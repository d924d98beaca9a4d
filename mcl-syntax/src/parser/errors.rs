//! The grammar's errors as diagnostics.

use crate::diag::{codes, Diagnostic};
use crate::lexer::Token;
use crate::span::Span;
use chumsky::error::{Rich, RichPattern, RichReason};
use chumsky::span::SimpleSpan;

fn describe_expected(expected: &[RichPattern<'_, Token<'_>>]) -> String {
    let mut names: Vec<String> = expected
        .iter()
        .filter_map(|p| match p {
            RichPattern::Token(t) => Some(format!("{}", &**t)),
            RichPattern::Label(l) => Some(l.to_string()),
            RichPattern::Identifier(i) => Some(format!("`{i}`")),
            RichPattern::EndOfInput => Some("end of file".to_string()),
            _ => None,
        })
        .collect();
    names.sort();
    names.dedup();
    match names.len() {
        0 => "something else".to_string(),
        1 => names.remove(0),
        _ => {
            let last = names.pop().expect("len >= 2");
            format!("{} or {}", names.join(", "), last)
        }
    }
}

/// A grammar error as a diagnostic: a custom error keeps its code and help
/// (see [`super::grammar::custom`]), any other says what was expected.
pub(super) fn rich_to_diagnostic(e: Rich<'_, Token<'_>, SimpleSpan>) -> Diagnostic {
    let span = Span::from(*e.span());
    match e.reason() {
        RichReason::Custom(msg) => {
            let mut parts = msg.splitn(3, '\u{1}');
            let code = parts.next().unwrap_or(codes::UNEXPECTED_TOKEN);
            let code = [codes::EMPTY_BLOCK, codes::MISSING_COMMAND, codes::UNEXPECTED_TOKEN]
                .into_iter()
                .find(|c| *c == code)
                .unwrap_or(codes::UNEXPECTED_TOKEN);
            let message = parts.next().unwrap_or("syntax error").to_string();
            let mut d = Diagnostic::error(code, message, span);
            if let Some(help) = parts.next().filter(|h| !h.is_empty()) {
                d = d.with_help(help);
            }
            d
        }
        RichReason::ExpectedFound { expected, found } => {
            let expected_s = describe_expected(expected);
            let found_s = match found {
                Some(t) => format!("{}", &**t),
                None => "end of file".to_string(),
            };
            let mut d =
                Diagnostic::error(codes::UNEXPECTED_TOKEN, format!("expected {expected_s}, found {found_s}"), span)
                    .with_label(span, format!("unexpected {found_s}"));
            if let Some(Token::Kw(k)) = found.as_deref() {
                if expected.iter().any(|p| matches!(p, RichPattern::Label(l) if l == "identifier")) {
                    d = d.with_help(format!("`{}` is a keyword and cannot be used as a name", k.as_str()));
                }
            }
            if let Some(Token::Num(_)) = found.as_deref() {
                if expected.iter().any(|p| matches!(p, RichPattern::Token(t) if **t == Token::RParen)) {
                    d = d.with_help("separate arguments with `,`");
                }
            }
            d
        }
    }
}
