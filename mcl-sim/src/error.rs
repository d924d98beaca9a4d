//! Errors of the simulator's input files, located at `file:line:column`
//! like the scenario loader's (`mcl_runtime::scenario`).

use std::ops::Range;

/// `origin:line:col: message`, with the line quoted and the span underlined.
pub fn located(origin: &str, text: &str, span: Range<usize>, message: &str) -> String {
    let start = span.start.min(text.len());
    let end = span.end.min(text.len()).max(start);
    let before = &text[..start];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    let src = text.lines().nth(line - 1).unwrap_or("");
    let width = text[start..end].lines().next().map_or(1, |s| s.chars().count().max(1));
    format!("{origin}:{line}:{col}: {message}\n{line:>4} | {src}\n     | {}{}", " ".repeat(col - 1), "^".repeat(width))
}

/// A TOML parse or type error, located when the parser knows where.
pub fn toml_error(origin: &str, text: &str, e: &toml::de::Error) -> String {
    let msg = e.message().trim_end();
    match e.span() {
        Some(span) => located(origin, text, span, msg),
        None => format!("{origin}: {msg}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_at_line_and_column() {
        let text = "a = 1\nbb = \"x\"\n";
        let e = located("f.toml", text, 11..14, "bad");
        assert!(e.starts_with("f.toml:2:6: bad\n"), "{e}");
        assert!(e.contains("   2 | bb = \"x\"\n     |      ^^^"), "{e}");
    }
}
