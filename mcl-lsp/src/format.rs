//! Whole-document formatting through `mcl_syntax::format`, as one minimal
//! edit (the changed middle of the text), so that the client keeps the
//! cursor and the undo history small.

use crate::analysis::Analysis;
use mcl_compiler::queries::parse;
use mcl_compiler::SourceFile;
use mcl_syntax::Span;
use tower_lsp_server::ls_types::TextEdit;

/// Whether the server can format documents.
pub const AVAILABLE: bool = true;

/// The edits that format `file`: none when it is formatted already, `None`
/// when it cannot be formatted (syntax errors).
pub fn format_document(a: &Analysis<'_>, file: SourceFile) -> Option<Vec<TextEdit>> {
    let text = a.text(file);
    let formatted = mcl_syntax::format::format_parse(text, parse(a.db, file)).ok()?;
    // Keep the document's line ends (the formatter writes `\n`).
    let formatted = crate::analysis::with_line_ends(&formatted, text).0;
    if formatted == text {
        return Some(Vec::new());
    }
    let span = changed(text, &formatted);
    let new_text = formatted[span.start as usize..formatted.len() - (text.len() - span.end as usize)].to_string();
    Some(vec![TextEdit { range: a.range(file, span), new_text }])
}

/// The span of `old` that differs from `new` (common prefix and suffix
/// removed, on character boundaries).
fn changed(old: &str, new: &str) -> Span {
    let mut prefix = old.bytes().zip(new.bytes()).take_while(|(a, b)| a == b).count();
    while !old.is_char_boundary(prefix) || !new.is_char_boundary(prefix) {
        prefix -= 1;
    }
    let max_suffix = old.len().min(new.len()) - prefix;
    let mut suffix = old.bytes().rev().zip(new.bytes().rev()).take(max_suffix).take_while(|(a, b)| a == b).count();
    while !old.is_char_boundary(old.len() - suffix) || !new.is_char_boundary(new.len() - suffix) {
        suffix -= 1;
    }
    Span::new(prefix, old.len() - suffix)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::fixture::{apply_edits, Fixture};

    #[test]
    fn minimal_edit_gives_the_formatted_text() {
        let text = "mission {\n  Void( ) ;Void()\n}\n";
        let f = Fixture::new(&[("a.mcl", text)]);
        let a = f.analysis();
        let edits = format_document(&a, f.file("a.mcl")).expect("formattable");
        let expected = mcl_syntax::format::format(text).unwrap();
        assert_eq!(apply_edits(text, &edits), expected);
        assert_eq!(edits.len(), 1);
        // Formatted already: no edit. Syntax errors: no formatting.
        let f = Fixture::new(&[("b.mcl", &expected), ("c.mcl", "mission { Void( }")]);
        let a = f.analysis();
        assert_eq!(format_document(&a, f.file("b.mcl")), Some(vec![]));
        assert_eq!(format_document(&a, f.file("c.mcl")), None);
    }

    #[test]
    fn changed_span_respects_characters() {
        assert_eq!(changed("aéb", "aèb"), Span::new(1, 3));
        assert_eq!(changed("abc", "abc"), Span::new(3, 3));
        assert_eq!(changed("ab", "abab"), Span::new(2, 2));
    }
}
