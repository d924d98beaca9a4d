//! S-expression reader for PDDL files: atoms, double-quoted strings (an MCL
//! extension, for string attributes and `:mcl` arguments), `;` comments.
//! Never panics; nesting is bounded so that hostile input cannot overflow the
//! stack.

use std::fmt;

/// Deepest nesting accepted (real PDDL files nest fewer than 20 levels).
pub const MAX_DEPTH: usize = 256;

/// A byte range in one source text.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Span {
    pub start: usize,
    pub end: usize,
}

/// One node of the tree.
#[derive(Clone, Debug, PartialEq)]
pub enum Sexpr {
    /// A symbol or a number, as written (case kept).
    Atom(String, Span),
    /// A double-quoted string, unescaped.
    Str(String, Span),
    List(Vec<Sexpr>, Span),
}

impl Sexpr {
    pub fn span(&self) -> Span {
        match self {
            Sexpr::Atom(_, s) | Sexpr::Str(_, s) | Sexpr::List(_, s) => *s,
        }
    }
    /// The atom's text in lower case (PDDL is case-insensitive).
    pub fn atom(&self) -> Option<String> {
        match self {
            Sexpr::Atom(a, _) => Some(a.to_ascii_lowercase()),
            _ => None,
        }
    }
    /// The atom's text as written.
    pub fn raw_atom(&self) -> Option<&str> {
        match self {
            Sexpr::Atom(a, _) => Some(a),
            _ => None,
        }
    }
    pub fn list(&self) -> Option<&[Sexpr]> {
        match self {
            Sexpr::List(l, _) => Some(l),
            _ => None,
        }
    }
    /// A short description for error messages.
    pub fn describe(&self) -> String {
        match self {
            Sexpr::Atom(a, _) => format!("`{a}`"),
            Sexpr::Str(s, _) => format!("the string \"{s}\""),
            Sexpr::List(l, _) => match l.first().and_then(|h| h.raw_atom()) {
                Some(h) => format!("a list starting with `{h}`"),
                None if l.is_empty() => "an empty list `()`".to_string(),
                None => "a list".to_string(),
            },
        }
    }
}

/// A located error: `file:line:column: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Error {
    pub file: String,
    /// 1-based.
    pub line: usize,
    /// 1-based, in characters.
    pub column: usize,
    pub message: String,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: {}", self.file, self.line, self.column, self.message)
    }
}

/// Converts byte offsets of one text to lines and columns.
#[derive(Clone, Debug)]
pub struct Source<'a> {
    pub name: String,
    pub text: &'a str,
    line_starts: Vec<usize>,
}

impl<'a> Source<'a> {
    pub fn new(name: &str, text: &'a str) -> Self {
        let mut line_starts = vec![0];
        line_starts.extend(text.bytes().enumerate().filter(|(_, b)| *b == b'\n').map(|(i, _)| i + 1));
        Source { name: name.to_string(), text, line_starts }
    }
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.text.len());
        let line = match self.line_starts.binary_search(&offset) {
            Ok(i) => i,
            Err(i) => i - 1,
        };
        let start = self.line_starts[line];
        let col = self.text.get(start..offset).map(|s| s.chars().count()).unwrap_or(offset - start);
        (line + 1, col + 1)
    }
    pub fn error(&self, span: Span, message: impl Into<String>) -> Error {
        let (line, column) = self.line_col(span.start);
        Error { file: self.name.clone(), line, column, message: message.into() }
    }
}

fn is_delim(c: char) -> bool {
    c.is_whitespace() || matches!(c, '(' | ')' | ';' | '"')
}

/// Reads every top-level expression of `src`. Errors: unbalanced
/// parentheses, unterminated strings, nesting deeper than [`MAX_DEPTH`].
pub fn read(src: &Source<'_>) -> Result<Vec<Sexpr>, Error> {
    let text = src.text;
    // Stack of open lists: (items, start offset).
    let mut stack: Vec<(Vec<Sexpr>, usize)> = Vec::new();
    let mut top: Vec<Sexpr> = Vec::new();
    let mut it = text.char_indices().peekable();
    while let Some((i, c)) = it.next() {
        let node = match c {
            c if c.is_whitespace() => continue,
            ';' => {
                for (_, c) in it.by_ref() {
                    if c == '\n' {
                        break;
                    }
                }
                continue;
            }
            '(' => {
                if stack.len() >= MAX_DEPTH {
                    return Err(src
                        .error(Span { start: i, end: i + 1 }, format!("lists nested deeper than {MAX_DEPTH} levels")));
                }
                stack.push((Vec::new(), i));
                continue;
            }
            ')' => match stack.pop() {
                Some((items, start)) => Sexpr::List(items, Span { start, end: i + 1 }),
                None => return Err(src.error(Span { start: i, end: i + 1 }, "unexpected `)`: no list is open here")),
            },
            '"' => {
                let mut s = String::new();
                let mut end = None;
                while let Some((j, c)) = it.next() {
                    match c {
                        '"' => {
                            end = Some(j + 1);
                            break;
                        }
                        '\\' => match it.next() {
                            Some((_, e @ ('"' | '\\'))) => s.push(e),
                            Some((_, 'n')) => s.push('\n'),
                            Some((_, e)) => {
                                s.push('\\');
                                s.push(e)
                            }
                            None => break,
                        },
                        '\n' => break,
                        c => s.push(c),
                    }
                }
                match end {
                    Some(end) => Sexpr::Str(s, Span { start: i, end }),
                    None => {
                        return Err(src.error(
                            Span { start: i, end: i + 1 },
                            "unterminated string: expected a closing `\"` on the same line",
                        ))
                    }
                }
            }
            _ => {
                let mut end = i + c.len_utf8();
                while let Some(&(j, c)) = it.peek() {
                    if is_delim(c) {
                        break;
                    }
                    end = j + c.len_utf8();
                    it.next();
                }
                Sexpr::Atom(text[i..end].to_string(), Span { start: i, end })
            }
        };
        match stack.last_mut() {
            Some((items, _)) => items.push(node),
            None => top.push(node),
        }
    }
    if let Some((_, start)) = stack.pop() {
        return Err(src.error(
            Span { start, end: start + 1 },
            "unclosed `(`: expected a matching `)` before the end of the file",
        ));
    }
    Ok(top)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_lists_atoms_strings_comments() {
        let s = Source::new("t", "; c\n(a (b ?c) \"x y\" 3.5) ; end\n");
        let v = read(&s).unwrap();
        assert_eq!(v.len(), 1);
        let l = v[0].list().unwrap();
        assert_eq!(l[0].atom().unwrap(), "a");
        assert_eq!(l[2], Sexpr::Str("x y".into(), Span { start: 14, end: 19 }));
    }

    #[test]
    fn errors_are_located() {
        let s = Source::new("f.pddl", "(a\n  (b)");
        let e = read(&s).unwrap_err();
        assert_eq!((e.line, e.column), (1, 1));
        let s = Source::new("f.pddl", "(a)\n  )");
        let e = read(&s).unwrap_err();
        assert_eq!((e.line, e.column), (2, 3));
        assert!(e.to_string().starts_with("f.pddl:2:3: unexpected `)`"));
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let t = "(".repeat(100_000);
        assert!(read(&Source::new("d", &t)).is_err());
    }
}
