//! The lexer: text to tokens, comments kept aside as trivia. It never fails:
//! characters it cannot use are reported and skipped.

use crate::diag::{codes, Diagnostic};
use crate::span::Span;
use std::fmt;

/// Reserved words. Constraint kinds (`mutex`, `_order_`, ...), the task binding
/// markers `a:`/`e:` and the action markers `c:`/`v:` are contextual and lexed
/// as identifiers, so they stay usable as names elsewhere.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kw {
    Import,
    Actions,
    Events,
    Pattern,
    Patterns,
    Tasks,
    Mission,
    PlanOp,
    Constraints,
    Places,
    Transitions,
    Arcs,
    While,
    If,
    Then,
    Else,
    Do,
    Parallel,
    And,
    Or,
    Try,
    Catch,
    Not,
    Monitor,
    Condition,
    WhileCondition,
    /// `planning { ... }`: the planning model (seed chapter 7).
    Planning,
    /// `pddl_map { ... }`: PDDL actions to MCL mission operators.
    PddlMap,
}

impl Kw {
    pub const ALL: [Kw; 28] = [
        Kw::Import,
        Kw::Actions,
        Kw::Events,
        Kw::Pattern,
        Kw::Patterns,
        Kw::Tasks,
        Kw::Mission,
        Kw::PlanOp,
        Kw::Constraints,
        Kw::Places,
        Kw::Transitions,
        Kw::Arcs,
        Kw::While,
        Kw::If,
        Kw::Then,
        Kw::Else,
        Kw::Do,
        Kw::Parallel,
        Kw::And,
        Kw::Or,
        Kw::Try,
        Kw::Catch,
        Kw::Not,
        Kw::Monitor,
        Kw::Condition,
        Kw::WhileCondition,
        Kw::Planning,
        Kw::PddlMap,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Kw::Import => "import",
            Kw::Actions => "actions",
            Kw::Events => "events",
            Kw::Pattern => "pattern",
            Kw::Patterns => "patterns",
            Kw::Tasks => "tasks",
            Kw::Mission => "mission",
            Kw::PlanOp => "mcl_plan_op",
            Kw::Constraints => "constraints",
            Kw::Places => "places",
            Kw::Transitions => "transitions",
            Kw::Arcs => "arcs",
            Kw::While => "while",
            Kw::If => "if",
            Kw::Then => "then",
            Kw::Else => "else",
            Kw::Do => "do",
            Kw::Parallel => "parallel",
            Kw::And => "and",
            Kw::Or => "or",
            Kw::Try => "try",
            Kw::Catch => "catch",
            Kw::Not => "not",
            Kw::Monitor => "monitor",
            Kw::Condition => "condition",
            Kw::WhileCondition => "while_condition",
            Kw::Planning => "planning",
            Kw::PddlMap => "pddl_map",
        }
    }

    /// The keyword written `s`, if it is one.
    pub fn from_word(s: &str) -> Option<Kw> {
        Kw::ALL.iter().copied().find(|k| k.as_str() == s)
    }

    /// Keywords that start a top-level item.
    pub fn starts_item(self) -> bool {
        matches!(
            self,
            Kw::Import
                | Kw::Actions
                | Kw::Events
                | Kw::Pattern
                | Kw::Patterns
                | Kw::Tasks
                | Kw::Mission
                | Kw::PlanOp
                | Kw::Constraints
                | Kw::Planning
                | Kw::PddlMap
        )
    }
}

/// One token; identifiers, numbers and strings borrow their text from the source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Token<'src> {
    Ident(&'src str),
    /// A number as written, e.g. `-2` or `15.5`.
    Num(&'src str),
    /// A string literal including its quotes, as written.
    Str(&'src str),
    Kw(Kw),
    LBrace,
    RBrace,
    LParen,
    RParen,
    LBracket,
    RBracket,
    Semi,
    Colon,
    Comma,
    Dot,
    Eq,
    /// `->` or `→`.
    Arrow,
    /// A comparison of a planning expression: `!=`, `==`, `<`, `<=`, `>`, `>=`.
    Cmp(&'src str),
}

impl fmt::Display for Token<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Token::Ident(s) => write!(f, "identifier `{s}`"),
            Token::Num(s) => write!(f, "number `{s}`"),
            Token::Str(s) => write!(f, "string {s}"),
            Token::Kw(k) => write!(f, "keyword `{}`", k.as_str()),
            Token::LBrace => f.write_str("`{`"),
            Token::RBrace => f.write_str("`}`"),
            Token::LParen => f.write_str("`(`"),
            Token::RParen => f.write_str("`)`"),
            Token::LBracket => f.write_str("`[`"),
            Token::RBracket => f.write_str("`]`"),
            Token::Semi => f.write_str("`;`"),
            Token::Colon => f.write_str("`:`"),
            Token::Comma => f.write_str("`,`"),
            Token::Dot => f.write_str("`.`"),
            Token::Eq => f.write_str("`=`"),
            Token::Arrow => f.write_str("`->`"),
            Token::Cmp(s) => write!(f, "`{s}`"),
        }
    }
}

/// The kind of a comment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CommentKind {
    /// `// ...` up to the end of the line (the newline is not part of it).
    Line,
    /// `/* ... */`.
    Block,
}

/// A comment, kept as trivia so that the formatter and the editor can use it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Comment {
    pub kind: CommentKind,
    pub span: Span,
}

/// The result of lexing: tokens with spans, comments, and lexical errors.
#[derive(Debug, Default)]
pub struct Lexed<'src> {
    pub tokens: Vec<(Token<'src>, Span)>,
    pub comments: Vec<Comment>,
    pub errors: Vec<Diagnostic>,
}

fn is_ident_start(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_' || c == '$'
}

fn is_ident_continue(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '_' | '$' | '-' | '/')
}

/// A letter (or a combining accent) outside ASCII, which identifiers may not hold.
fn is_foreign_letter(c: char) -> bool {
    !c.is_ascii() && (c.is_alphanumeric() || ('\u{300}'..='\u{36f}').contains(&c))
}

/// The ASCII spelling of a Latin letter with a diacritic, if it has one.
fn ascii_of(c: char) -> Option<&'static str> {
    const FOLDS: [(&str, &str); 14] = [
        ("àáâãäåāăą", "a"),
        ("ÀÁÂÃÄÅĀĂĄ", "A"),
        ("çćĉċč", "c"),
        ("ÇĆĈĊČ", "C"),
        ("èéêëēĕėęě", "e"),
        ("ÈÉÊËĒĔĖĘĚ", "E"),
        ("ìíîïĩīĭį", "i"),
        ("ÌÍÎÏĨĪĬĮ", "I"),
        ("ñńņň", "n"),
        ("ÑŃŅŇ", "N"),
        ("òóôõöøōŏő", "o"),
        ("ÒÓÔÕÖØŌŎŐ", "O"),
        ("ùúûüũūŭůűų", "u"),
        ("ÙÚÛÜŨŪŬŮŰŲ", "U"),
    ];
    if ('\u{300}'..='\u{36f}').contains(&c) {
        return Some("");
    }
    match c {
        'ß' => return Some("ss"),
        'æ' => return Some("ae"),
        'Æ' => return Some("AE"),
        'œ' => return Some("oe"),
        'Œ' => return Some("OE"),
        'ý' | 'ÿ' => return Some("y"),
        'Ý' => return Some("Y"),
        _ => {}
    }
    FOLDS.iter().find(|(from, _)| from.contains(c)).map(|(_, to)| *to)
}

/// The one error of an identifier that holds a letter outside ASCII, with
/// its ASCII spelling when every such letter has one.
fn foreign_letter(text: &str, span: Span, c: char) -> Diagnostic {
    let ascii: Option<String> = text
        .chars()
        .map(|c| if c.is_ascii() { Some(c.to_string()) } else { ascii_of(c).map(str::to_string) })
        .collect();
    let mut help = "identifiers are ASCII: letters a-z A-Z, digits, `_`, `$`, `-`, `/`".to_string();
    if let Some(a) = ascii.filter(|a| !a.is_empty()) {
        help.push_str(&format!("; write `{a}`"));
    }
    Diagnostic::error(codes::UNKNOWN_CHAR, format!("identifier `{text}` has the non-ASCII letter `{c}`"), span)
        .with_label(span, format!("`{c}` is not an ASCII letter"))
        .with_help(help)
}

/// Splits `src` into tokens. Never fails: unknown characters become errors.
pub fn lex(src: &str) -> Lexed<'_> {
    lex_before(src, false)
}

/// [`lex`] for a text that a word follows in its file (an item cut before
/// the next item's keyword): the tokens and errors are the ones the whole
/// file gives for this part (`1.` right before the keyword is the number
/// `1` and a `.`, as in `1.tasks`, not a malformed number).
pub fn lex_before(src: &str, word_follows: bool) -> Lexed<'_> {
    let mut l = Lexer::new(src);
    l.word_follows = word_follows;
    l.out.tokens.reserve(src.len() / 4);
    while l.step() {}
    l.out
}

/// A lexer that runs on demand: [`Lexer::step`] lexes one more token,
/// comment, error or run of whitespace. Running it to the end gives [`lex`].
/// Lexing never looks back: started at the first byte of a token of a file,
/// it gives that file's tokens from there (spans relative to its start).
#[derive(Debug)]
pub struct Lexer<'src> {
    src: &'src str,
    i: usize,
    /// What was lexed so far.
    pub out: Lexed<'src>,
    /// A word follows `src` in its file ([`lex_before`]).
    word_follows: bool,
}

impl<'src> Lexer<'src> {
    pub fn new(src: &'src str) -> Self {
        Lexer { src, i: 0, out: Lexed::default(), word_follows: false }
    }

    /// Lexes one more piece of the source; `false` at the end.
    #[inline]
    pub fn step(&mut self) -> bool {
        if self.i >= self.src.len() {
            return false;
        }
        self.i = lex_one(self.src, self.i, &mut self.out, self.word_follows);
        true
    }
}

/// Lexes the piece of `src` that starts at `i`; returns where the next starts.
#[inline]
fn lex_one<'src>(src: &'src str, mut i: usize, out: &mut Lexed<'src>, word_follows: bool) -> usize {
    let bytes = src.as_bytes();
    {
        let b = bytes[i];
        let start = i;
        // ASCII fast path; other characters are decoded below.
        match b {
            b' ' | b'\t' | b'\n' | b'\r' => {
                i += 1;
                return i;
            }
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                // To the line end: `\n`, `\r\n` or a lone `\r`.
                while i < bytes.len() && bytes[i] != b'\n' && bytes[i] != b'\r' {
                    i += 1;
                }
                let end = if i > start && bytes[i - 1] == b'\r' { i - 1 } else { i };
                out.comments.push(Comment { kind: CommentKind::Line, span: Span::new(start, end) });
                return i;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i += 2;
                let mut closed = false;
                while i < bytes.len() {
                    if bytes[i] == b'*' && bytes.get(i + 1) == Some(&b'/') {
                        i += 2;
                        closed = true;
                        break;
                    }
                    i += 1;
                }
                if !closed {
                    out.errors.push(
                        Diagnostic::error(
                            codes::UNTERMINATED_COMMENT,
                            "unterminated block comment",
                            Span::new(start, start + 2),
                        )
                        .with_help("close the comment with `*/`"),
                    );
                }
                out.comments.push(Comment { kind: CommentKind::Block, span: Span::new(start, i) });
                return i;
            }
            b'"' => {
                i += 1;
                let mut closed = false;
                while i < bytes.len() {
                    match bytes[i] {
                        b'\\' if i + 1 < bytes.len() && bytes[i + 1] != b'\n' => i += 2,
                        b'"' => {
                            i += 1;
                            closed = true;
                            break;
                        }
                        b'\n' => break,
                        _ => i += 1,
                    }
                }
                let i_end = i.min(bytes.len());
                // `i` may sit in the middle of a multi-byte char only if the
                // escape skipped into it; move to the next boundary.
                let mut end = i_end;
                while !src.is_char_boundary(end) {
                    end += 1;
                }
                if !closed {
                    // The string runs to the end of the line. If the line goes
                    // on with a delimiter or separator, the closing quote most
                    // likely belongs just before it (`Search( "cable ) ;`):
                    // end the string there so that the rest of the line is
                    // lexed as usual and one missing quote gives one error.
                    if let Some(p) =
                        bytes[start + 1..end].iter().position(|b| matches!(b, b')' | b']' | b'}' | b';' | b','))
                    {
                        end = start + 1 + p;
                    }
                }
                i = end;
                if !closed {
                    out.errors.push(
                        Diagnostic::error(codes::UNTERMINATED_STRING, "unterminated string", Span::new(start, end))
                            .with_help("add the closing `\"` on the same line"),
                    );
                }
                out.tokens.push((Token::Str(&src[start..end]), Span::new(start, end)));
                return i;
            }
            b'0'..=b'9' => {
                i = lex_number(src, i, out, word_follows);
                return i;
            }
            b'-' if bytes.get(i + 1).is_some_and(u8::is_ascii_digit) => {
                i = lex_number(src, i + 1, out, word_follows);
                // lex_number pushed a token starting after '-': widen it.
                if let Some((Token::Num(_), span)) = out.tokens.last_mut() {
                    *span = Span::new(start, span.end as usize);
                    let end = span.end as usize;
                    out.tokens.last_mut().expect("just pushed").0 = Token::Num(&src[start..end]);
                }
                return i;
            }
            b'-' if bytes.get(i + 1) == Some(&b'>') => {
                out.tokens.push((Token::Arrow, Span::new(i, i + 2)));
                i += 2;
                return i;
            }
            _ => {}
        }
        // Comparisons (planning expressions, docs/planning.md).
        let cmp_len = match (b, bytes.get(i + 1).copied()) {
            (b'!' | b'=' | b'<' | b'>', Some(b'=')) => 2,
            (b'<' | b'>', _) => 1,
            _ => 0,
        };
        if cmp_len > 0 {
            out.tokens.push((Token::Cmp(&src[i..i + cmp_len]), Span::new(i, i + cmp_len)));
            return i + cmp_len;
        }
        let punct = match b {
            b'{' => Some(Token::LBrace),
            b'}' => Some(Token::RBrace),
            b'(' => Some(Token::LParen),
            b')' => Some(Token::RParen),
            b'[' => Some(Token::LBracket),
            b']' => Some(Token::RBracket),
            b';' => Some(Token::Semi),
            b':' => Some(Token::Colon),
            b',' => Some(Token::Comma),
            b'.' => Some(Token::Dot),
            b'=' => Some(Token::Eq),
            _ => None,
        };
        if let Some(t) = punct {
            out.tokens.push((t, Span::new(i, i + 1)));
            i += 1;
            return i;
        }
        let c = src[i..].chars().next().expect("i is a char boundary inside src");
        if is_ident_start(c) || is_foreign_letter(c) {
            // A letter outside ASCII (`Plongée`) stays in the identifier, so
            // that it is one error and one name, not two names in a row.
            let mut foreign = (!c.is_ascii()).then_some(c);
            i += c.len_utf8();
            while i < bytes.len() {
                if !bytes[i].is_ascii() {
                    let c = src[i..].chars().next().expect("boundary");
                    if !is_foreign_letter(c) {
                        break;
                    }
                    foreign = foreign.or(Some(c));
                    i += c.len_utf8();
                    continue;
                }
                let c = bytes[i] as char;
                if !is_ident_continue(c) {
                    break;
                }
                // `-` before `>` is an arrow; `/` before `/` or `*` starts a comment.
                let next = bytes.get(i + 1).copied();
                if (c == '-' && next == Some(b'>')) || (c == '/' && matches!(next, Some(b'/') | Some(b'*'))) {
                    break;
                }
                i += 1;
            }
            let text = &src[start..i];
            if let Some(ch) = foreign {
                out.errors.push(foreign_letter(text, Span::new(start, i), ch));
            }
            let tok = match Kw::from_word(text) {
                Some(k) => Token::Kw(k),
                None => Token::Ident(text),
            };
            out.tokens.push((tok, Span::new(start, i)));
            return i;
        }
        if c == '→' {
            out.tokens.push((Token::Arrow, Span::new(i, i + c.len_utf8())));
            i += c.len_utf8();
            return i;
        }
        if c.is_whitespace() {
            i += c.len_utf8();
            return i;
        }
        // A byte order mark starts many files written on Windows: skipped.
        if c == '\u{feff}' && i == 0 {
            return i + c.len_utf8();
        }
        // `#` is a comment in many languages: report it and skip the line.
        if c == '#' {
            let mut end = i;
            while end < bytes.len() && bytes[end] != b'\n' && bytes[end] != b'\r' {
                end += 1;
            }
            out.errors.push(
                Diagnostic::error(codes::UNKNOWN_CHAR, "`#` does not start a comment in MCL", Span::new(i, i + 1))
                    .with_help("comments are written `// ...` or `/* ... */`"),
            );
            out.comments.push(Comment { kind: CommentKind::Line, span: Span::new(i, end) });
            i = end;
            return i;
        }
        // Skip a run of unknown characters and report it once.
        let mut end = i + c.len_utf8();
        while end < bytes.len() {
            let c2 = src[end..].chars().next().expect("boundary");
            if c2.is_whitespace() || c2.is_ascii_alphanumeric() || "{}()[];:,.=<>\"_$/".contains(c2) || c2 == '→' {
                break;
            }
            end += c2.len_utf8();
        }
        let shown = &src[i..end];
        let mut d = Diagnostic::error(
            codes::UNKNOWN_CHAR,
            format!(
                "unexpected character{} `{}`",
                if shown.chars().count() > 1 { "s" } else { "" },
                shown
                    .chars()
                    .flat_map(|c| if c.is_control() { c.escape_debug().collect::<Vec<_>>() } else { vec![c] })
                    .collect::<String>()
            ),
            Span::new(i, end),
        );
        if c == '≠' || c == '!' {
            d = d.with_help("MCL programs have no operators; expressions belong to planning operators");
        } else if c == '\'' {
            d = d.with_help("strings are written with double quotes: \"...\"");
        } else if c == '#' {
            d = d.with_help("comments are written `// ...` or `/* ... */`");
        }
        out.errors.push(d);
        end
    }
}

/// Lexes `[0-9]+(\.[0-9]+)?` starting at `i`; pushes the token; returns the
/// new position. `word_follows`: a word follows the end of `src`.
fn lex_number<'src>(src: &'src str, mut i: usize, out: &mut Lexed<'src>, word_follows: bool) -> usize {
    let bytes = src.as_bytes();
    let start = i;
    while i < bytes.len() && bytes[i].is_ascii_digit() {
        i += 1;
    }
    let int_len = i - start;
    let fraction = i + 1 < bytes.len() && bytes[i] == b'.' && bytes[i + 1].is_ascii_digit();
    if fraction {
        i += 1;
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
    }
    if !fraction
        && i < bytes.len()
        && bytes[i] == b'.'
        && !bytes.get(i + 1).map_or(word_follows, |&b| b.is_ascii_digit() || is_ident_start(b as char))
    {
        // `1.`: a fraction without digits. Take the dot into the number so
        // that the parser sees one (malformed) number.
        i += 1;
        out.errors.push(
            Diagnostic::error(codes::BAD_NUMBER, "number with a `.` but no digits after it", Span::new(start, i))
                .with_help("write the fraction's digits, or drop the `.`: `1` or `1.5`"),
        );
    }
    if int_len > 1 && bytes[start] == b'0' {
        out.errors.push(
            Diagnostic::error(codes::BAD_NUMBER, "number with a leading zero", Span::new(start, i))
                .with_help("write numbers without leading zeros, e.g. `7` or `0.5`"),
        );
    }
    out.tokens.push((Token::Num(&src[start..i]), Span::new(start, i)));
    i
}

/// Decodes a string literal token (with quotes) into its value.
pub fn unescape(raw: &str) -> String {
    let inner = raw.strip_prefix('"').unwrap_or(raw);
    let inner = inner.strip_suffix('"').unwrap_or(inner);
    let mut out = String::with_capacity(inner.len());
    let mut chars = inner.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some('n') => out.push('\n'),
                Some('t') => out.push('\t'),
                Some(other) => out.push(other),
                None => out.push('\\'),
            }
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(src: &str) -> Vec<Token<'_>> {
        lex(src).tokens.into_iter().map(|(t, _)| t).collect()
    }

    #[test]
    fn identifiers_with_dash_slash_dollar() {
        assert_eq!(kinds("way-point a/b $x"), vec![Token::Ident("way-point"), Token::Ident("a/b"), Token::Ident("$x")]);
    }

    #[test]
    fn arrows_end_identifiers() {
        assert_eq!(kinds("begin->T0"), vec![Token::Ident("begin"), Token::Arrow, Token::Ident("T0")]);
        assert_eq!(kinds("a → b"), vec![Token::Ident("a"), Token::Arrow, Token::Ident("b")]);
        // Comparisons of planning expressions; `=` alone stays `Eq`.
        assert_eq!(
            kinds("a!=b<=c<d>=e>f==g=h"),
            vec![
                Token::Ident("a"),
                Token::Cmp("!="),
                Token::Ident("b"),
                Token::Cmp("<="),
                Token::Ident("c"),
                Token::Cmp("<"),
                Token::Ident("d"),
                Token::Cmp(">="),
                Token::Ident("e"),
                Token::Cmp(">"),
                Token::Ident("f"),
                Token::Cmp("=="),
                Token::Ident("g"),
                Token::Eq,
                Token::Ident("h"),
            ]
        );
    }

    #[test]
    fn negative_and_decimal_numbers() {
        assert_eq!(
            kinds("-2 15.5 x -0.5"),
            vec![Token::Num("-2"), Token::Num("15.5"), Token::Ident("x"), Token::Num("-0.5")]
        );
        assert_eq!(kinds("begin.1"), vec![Token::Ident("begin"), Token::Dot, Token::Num("1")]);
        assert_eq!(kinds("a-2"), vec![Token::Ident("a-2")]);
    }

    #[test]
    fn comments_are_trivia() {
        let l = lex("a // x\n/* y */ b//z");
        assert_eq!(l.tokens.len(), 2);
        assert_eq!(l.comments.len(), 3);
        assert!(l.errors.is_empty());
        // A line comment ends at `\r\n` or a lone `\r` too (old Mac files).
        let l = lex("a // x\rb // y\r\nc");
        assert_eq!(l.tokens.len(), 3);
        assert_eq!(l.comments.iter().map(|c| c.span.range()).collect::<Vec<_>>(), [2..6, 9..13]);
    }

    #[test]
    fn errors_do_not_stop_lexing() {
        let l = lex("a @ b \"open\n c /* never");
        assert_eq!(l.errors.len(), 3);
        assert!(l.tokens.iter().any(|(t, _)| *t == Token::Ident("c")));
    }

    #[test]
    fn strings_unescape() {
        assert_eq!(unescape(r#""a\"b\\c""#), "a\"b\\c");
    }
}
