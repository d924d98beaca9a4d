//! Byte spans and line/column conversion.

use serde::{Deserialize, Serialize};

/// A half-open byte range `start..end` into one source text.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Span {
    pub start: u32,
    pub end: u32,
}

impl Span {
    /// Builds a span; `end` is clamped so that it is never before `start`.
    pub fn new(start: usize, end: usize) -> Self {
        Span { start: start as u32, end: end.max(start) as u32 }
    }
    /// An empty span at `offset`.
    pub fn at(offset: usize) -> Self {
        Span::new(offset, offset)
    }
    /// The smallest span that covers both.
    pub fn cover(self, other: Span) -> Span {
        Span { start: self.start.min(other.start), end: self.end.max(other.end) }
    }
    pub fn range(self) -> std::ops::Range<usize> {
        self.start as usize..self.end as usize
    }
    pub fn len(self) -> usize {
        (self.end - self.start) as usize
    }
    pub fn is_empty(self) -> bool {
        self.start == self.end
    }
    pub fn contains(self, offset: usize) -> bool {
        (self.start as usize) <= offset && offset <= (self.end as usize)
    }
}

impl From<chumsky::span::SimpleSpan> for Span {
    fn from(s: chumsky::span::SimpleSpan) -> Self {
        Span::new(s.start, s.end)
    }
}

/// A 1-based line and a 1-based column counted in characters (Unicode scalar values).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct LineCol {
    pub line: u32,
    pub column: u32,
}

/// Maps byte offsets of a text to lines and columns (1-based, characters) and to
/// LSP positions (0-based, UTF-16 code units), and back.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LineIndex {
    line_starts: Vec<u32>,
    len: u32,
}

impl LineIndex {
    /// Lines end at `\n`, `\r\n` or a lone `\r`, as the language server
    /// protocol counts them (and editors show them).
    pub fn new(text: &str) -> Self {
        let bytes = text.as_bytes();
        let mut line_starts = vec![0u32];
        for (i, &b) in bytes.iter().enumerate() {
            if b == b'\n' || (b == b'\r' && bytes.get(i + 1) != Some(&b'\n')) {
                line_starts.push(i as u32 + 1);
            }
        }
        LineIndex { line_starts, len: text.len() as u32 }
    }

    /// Number of lines (a text ending with a newline has an empty last line).
    pub fn line_count(&self) -> usize {
        self.line_starts.len()
    }

    /// 0-based line of a byte offset.
    pub fn line_of(&self, offset: usize) -> usize {
        let offset = offset.min(self.len as usize) as u32;
        match self.line_starts.binary_search(&offset) {
            Ok(i) => i,
            Err(i) => i - 1,
        }
    }

    /// Byte offset where the 0-based `line` starts (the end of the text past the last line).
    pub fn line_start(&self, line: usize) -> usize {
        self.line_starts.get(line).map_or(self.len as usize, |&s| s as usize)
    }

    /// 1-based line and character column of a byte offset (clamped to a char boundary).
    pub fn line_col(&self, text: &str, offset: usize) -> LineCol {
        let offset = floor_char_boundary(text, offset);
        let line = self.line_of(offset);
        let start = self.line_start(line);
        let mut column = text[start..offset].chars().count() + 1;
        // A byte order mark is not a column of the first line.
        if line == 0 && offset > 0 && text.starts_with('\u{feff}') {
            column -= 1;
        }
        LineCol { line: line as u32 + 1, column: column as u32 }
    }

    /// Byte offset where the 0-based `line`'s content ends (before its line end).
    pub fn line_end(&self, text: &str, line: usize) -> usize {
        let start = self.line_start(line);
        let mut end = self.line_start(line + 1).min(text.len()).max(start);
        let b = text.as_bytes();
        if end > start && b[end - 1] == b'\n' {
            end -= 1;
        }
        if end > start && b[end - 1] == b'\r' {
            end -= 1;
        }
        end
    }

    /// 0-based line and UTF-16 column, as the language server protocol
    /// counts. An offset inside a line end is placed at the end of the line.
    pub fn utf16_position(&self, text: &str, offset: usize) -> (u32, u32) {
        let offset = floor_char_boundary(text, offset);
        let line = self.line_of(offset);
        let start = self.line_start(line);
        let offset = offset.min(self.line_end(text, line));
        let col: usize = text[start..offset].chars().map(char::len_utf16).sum();
        (line as u32, col as u32)
    }

    /// Byte offset of a 0-based line and UTF-16 column. A column past the
    /// end of its line is the end of the line (never inside its line end), a
    /// line past the last is the end of the text, a column inside a
    /// character's surrogate pair is the character's end.
    pub fn offset_of_utf16(&self, text: &str, line: u32, col: u32) -> usize {
        if line as usize >= self.line_starts.len() {
            return text.len();
        }
        let start = self.line_start(line as usize);
        let end = self.line_end(text, line as usize);
        let mut units = 0u32;
        for (i, c) in text[start..end].char_indices() {
            if units >= col {
                return start + i;
            }
            units += c.len_utf16() as u32;
        }
        end
    }
}

fn floor_char_boundary(text: &str, offset: usize) -> usize {
    let mut o = offset.min(text.len());
    while !text.is_char_boundary(o) {
        o -= 1;
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_col_counts_characters() {
        let text = "ab\nçé x\n";
        let idx = LineIndex::new(text);
        assert_eq!(idx.line_col(text, 0), LineCol { line: 1, column: 1 });
        assert_eq!(idx.line_col(text, 3), LineCol { line: 2, column: 1 });
        let x = text.find('x').unwrap();
        assert_eq!(idx.line_col(text, x), LineCol { line: 2, column: 4 });
        assert_eq!(idx.line_col(text, text.len()), LineCol { line: 3, column: 1 });
        assert_eq!(idx.utf16_position(text, x), (1, 3));
        assert_eq!(idx.offset_of_utf16(text, 1, 3), x);
        assert_eq!(idx.offset_of_utf16(text, 9, 0), text.len());
    }

    #[test]
    fn a_byte_order_mark_is_no_column() {
        let text = "\u{feff}mission {\n}";
        let idx = LineIndex::new(text);
        assert_eq!(idx.line_col(text, 3), LineCol { line: 1, column: 1 });
        assert_eq!(idx.line_col(text, text.find('{').unwrap()), LineCol { line: 1, column: 9 });
        assert_eq!(idx.line_col(text, text.find('}').unwrap()), LineCol { line: 2, column: 1 });
    }

    #[test]
    fn every_line_end_counts_and_positions_stay_outside_them() {
        // `\n`, `\r\n` and a lone `\r` end lines, as LSP clients count them.
        let text = "a\r\nbc\rd\n\r\ne";
        let idx = LineIndex::new(text);
        assert_eq!(idx.line_count(), 5);
        let e = text.find('e').unwrap();
        assert_eq!(idx.utf16_position(text, e), (4, 0));
        assert_eq!(idx.utf16_position(text, text.find('d').unwrap()), (2, 0));
        // Inside `\r\n`, on a lone `\r`: the end of the line.
        assert_eq!(idx.utf16_position(text, 2), (0, 1));
        assert_eq!(idx.utf16_position(text, 5), (1, 2));
        // A column past the end of a line stops before its line end.
        assert_eq!(idx.offset_of_utf16(text, 0, 5), 1);
        assert_eq!(idx.offset_of_utf16(text, 1, 9), 5);
        assert_eq!(idx.offset_of_utf16(text, 3, 3), text.find("\r\ne").unwrap());
        assert_eq!(idx.offset_of_utf16(text, 4, 9), text.len());
        for line in 0..6 {
            for col in 0..6 {
                let o = idx.offset_of_utf16(text, line, col);
                assert!(text.is_char_boundary(o));
                assert!(!(o > 0 && text.as_bytes()[o - 1] == b'\r' && text.as_bytes().get(o) == Some(&b'\n')));
            }
        }
    }

    #[test]
    fn astral_characters_take_two_utf16_units() {
        let text = "𝄞x\n😀😀y";
        let idx = LineIndex::new(text);
        assert_eq!(idx.utf16_position(text, text.find('x').unwrap()), (0, 2));
        assert_eq!(idx.utf16_position(text, text.find('y').unwrap()), (1, 4));
        assert_eq!(idx.offset_of_utf16(text, 0, 2), text.find('x').unwrap());
        assert_eq!(idx.offset_of_utf16(text, 1, 4), text.find('y').unwrap());
        // Inside a surrogate pair: after the character, on a boundary.
        assert_eq!(idx.offset_of_utf16(text, 0, 1), text.find('x').unwrap());
        // Offsets inside a character are taken back to its start.
        assert_eq!(idx.utf16_position(text, 1), (0, 0));
    }
}
