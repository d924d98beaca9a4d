//! The formatter: one canonical layout for every MCL file.
//!
//! [`format`] parses the text, refuses it if it has syntax errors, and prints
//! the tree again in the canonical style, keeping every comment:
//!
//! - 4 spaces per level; one top-level item, definition, binding, statement or
//!   constraint per line; a blank line between top-level items (two imports
//!   may follow each other); elsewhere a blank line of the input is kept (at
//!   most one), except just after an opening brace.
//! - The canonical spellings of `docs/language.md` section 11: `->` for `→`,
//!   `pattern` for `patterns`, `mutex`/`order`/`sync` for `_mutex_`/`_order_`/
//!   `_sync_`, `else` for the `then` of Table B.4, parentheses around every
//!   condition (`if ( A ) {`, `while ( A ) {`, `condition ( B ) do {`) and
//!   around the body of `not`, no `then` after an if condition nor `do` after
//!   a while condition. The two mission headers `mission Name( ... )` and
//!   `mcl_plan_op Name( ... )` are different constructs and stay as written,
//!   and so do string literals, numbers and the path of a PNML pattern.
//! - A `;` between statements ends the line, after a space (`A ;`); the
//!   tolerated `;` after the last statement of a block, the optional `;`
//!   after a constraint and trailing commas are dropped. Blocks always open
//!   at the end of a line and close on their own line (`} else {`,
//!   `} or {`, `} condition ( B ) do {`); a block with nothing in it is `{ }`.
//! - A condition (or the body of `not`) made of calls and `not`s only is
//!   written on one line: `while ( not ( Done() ) ) {`; one holding another
//!   control structure is written over several lines, like a block.
//! - Calls `Name( a, b ) : label` and `Name()`, lists `[1, 2]`, tagged lists
//!   `path[[0, 0], [1, 1]]`, actions `a = P( c: enable, v: x );` (the
//!   command first), places `p.1(2);`, transitions `T(30);`, arcs
//!   `p -> t (2);`, bindings `a: x -> T1, T2;`, tasks `Goto( wp ): P {`,
//!   constraints `mutex { m:a, b } = 1`, missions `mission : auv [ x at 0 ] {`.
//!   Lines are never wrapped: MCL has no expressions to break.
//!
//! Comments stay next to the token they were next to. A comment on its own
//! line stays on its own line, at the indentation of what follows it (a
//! blank line before it is kept); a comment after code on the same line
//! stays at the end of that line (a `// ...` comment is moved past the `;`,
//! `,`, `)`, `]`, `{`, `}` or `do` that follow it, so `A // c` + `;` gives
//! `A ; // c`); a `/* ... */` comment between two tokens of a line stays
//! between them. When a `// ...` comment sits where the canonical layout has
//! no line break, the line is broken after it: before `else`, `and`, `or`,
//! `catch`, `condition` and `while_condition` the next line starts at the
//! same level, elsewhere it continues one level deeper.
//!
//! The result is checked before it is returned: it must parse without errors
//! to the same tree (modulo spans and spellings) with the same comments.

use crate::ast::*;
use crate::diag::Diagnostic;
use crate::lexer::{lex, CommentKind, Kw, Token};
use crate::parser::Parse;
use crate::span::Span;
use std::fmt;

const INDENT: &str = "    ";

/// Why a text was not formatted.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FormatError {
    /// The text has syntax errors (only the errors, not the warnings): a file
    /// is only formatted when it parses cleanly.
    Syntax(Vec<Diagnostic>),
    /// The formatted text would not mean the same as the input. This is a bug
    /// of the formatter; the input is left alone.
    Internal(String),
}

impl fmt::Display for FormatError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FormatError::Syntax(errors) => {
                let n = errors.len();
                write!(f, "{n} syntax error{}", if n == 1 { "" } else { "s" })?;
                if let Some(first) = errors.first() {
                    write!(f, ": {} ({})", first.message, first.code)?;
                }
                Ok(())
            }
            FormatError::Internal(msg) => write!(f, "internal formatter error: {msg}"),
        }
    }
}

impl std::error::Error for FormatError {}

/// Formats a whole file in the canonical style. Refuses a text with syntax
/// errors (warnings such as W0015 do not prevent formatting).
pub fn format(text: &str) -> Result<String, FormatError> {
    format_parse(text, &crate::parse(text))
}

/// As [`format`], for a text already parsed (`parse` must be `parse(text)`).
pub fn format_parse(text: &str, parse: &Parse) -> Result<String, FormatError> {
    let errors: Vec<Diagnostic> = parse.errors.iter().filter(|d| d.is_error()).cloned().collect();
    if !errors.is_empty() {
        return Err(FormatError::Syntax(errors));
    }
    let out = Printer::new(text, parse).file(&parse.file);
    // The promise: same tree, same comments, and nothing that does not parse.
    let again = crate::parse(&out);
    if let Some(e) = again.errors.iter().find(|d| d.is_error()) {
        return Err(FormatError::Internal(format!("the formatted text does not parse: {} ({})", e.message, e.code)));
    }
    if normalize(&again.file) != normalize(&parse.file) {
        return Err(FormatError::Internal("the formatted text parses to a different tree".into()));
    }
    let texts = |t: &str, p: &Parse| {
        let mut v: Vec<String> = p.comments.iter().map(|c| comment_text(t, c.kind, c.span)).collect();
        v.sort();
        v
    };
    if texts(text, parse) != texts(&out, &again) {
        return Err(FormatError::Internal("the formatted text does not have the same comments".into()));
    }
    Ok(out)
}

/// The text of a comment as the formatter writes it: a line comment without
/// trailing white space, a block comment with `\n` line ends.
pub fn comment_text(src: &str, kind: CommentKind, span: Span) -> String {
    let raw = &src[span.range()];
    match kind {
        CommentKind::Line => raw.trim_end().to_string(),
        CommentKind::Block => raw.replace("\r\n", "\n"),
    }
}

// ---------------------------------------------------------------------------
// Normalized trees: what formatting must not change.

/// A copy of `file` with every span zeroed and every accepted spelling
/// replaced by the canonical one (`_mutex_` by `mutex`, the `then` of Table
/// B.4 by `else`): two texts that mean the same have equal normalized trees.
pub fn normalize(file: &SourceFile) -> SourceFile {
    let mut f = file.clone();
    for item in &mut f.items {
        norm_item(item);
    }
    f
}

const Z: Span = Span { start: 0, end: 0 };

fn norm_item(item: &mut Item) {
    match item {
        Item::Import(i) => {
            i.path_span = Z;
            i.span = Z;
        }
        Item::Actions(a) => {
            a.span = Z;
            for d in &mut a.actions {
                d.span = Z;
                d.name.span = Z;
                d.primitive.span = Z;
                if let Some(c) = &mut d.command {
                    c.span = Z;
                }
                d.params.iter_mut().for_each(norm_value);
            }
        }
        Item::Events(e) => {
            e.span = Z;
            e.events.iter_mut().for_each(|n| n.span = Z);
        }
        Item::Patterns(p) => {
            p.span = Z;
            for pat in &mut p.patterns {
                pat.span = Z;
                pat.name.span = Z;
                match &mut pat.body {
                    PatternBody::File { path_span, .. } => *path_span = Z,
                    PatternBody::Net(net) => {
                        for pl in &mut net.places {
                            pl.span = Z;
                            pl.name.span = Z;
                            norm_num(&mut pl.interface);
                            norm_num(&mut pl.tokens);
                        }
                        for t in &mut net.transitions {
                            t.span = Z;
                            t.name.span = Z;
                            norm_num(&mut t.interface);
                            match &mut t.delay {
                                Some(Delay::Fixed(n)) => n.span = Z,
                                Some(Delay::Param(n)) => n.span = Z,
                                None => {}
                            }
                        }
                        for a in &mut net.arcs {
                            a.span = Z;
                            for r in [&mut a.source, &mut a.target] {
                                r.name.span = Z;
                                norm_num(&mut r.interface);
                            }
                            norm_num(&mut a.weight);
                        }
                    }
                }
            }
        }
        Item::Tasks(t) => {
            t.span = Z;
            for task in &mut t.tasks {
                task.span = Z;
                task.name.span = Z;
                task.params.iter_mut().for_each(|n| n.span = Z);
                if let Some(p) = &mut task.pattern {
                    p.span = Z;
                }
                for b in &mut task.bindings {
                    b.span = Z;
                    b.target.span = Z;
                    b.transitions.iter_mut().for_each(|n| n.span = Z);
                }
            }
        }
        Item::Mission(m) => {
            m.keyword_span = Z;
            m.span = Z;
            if let Some(n) = &mut m.name {
                n.span = Z;
            }
            m.params.iter_mut().for_each(|n| n.span = Z);
            if let Some((n, k)) = &mut m.placement {
                n.span = Z;
                k.span = Z;
            }
            norm_block(&mut m.body);
        }
        Item::Constraints(c) => {
            c.span = Z;
            for k in &mut c.constraints {
                k.span = Z;
                k.keyword_span = Z;
                k.bnf_spelling = false;
                norm_num(&mut k.bound);
                for r in &mut k.refs {
                    r.span = Z;
                    r.label.span = Z;
                    if let Some(m) = &mut r.mission {
                        m.span = Z;
                    }
                }
            }
        }
        Item::Planning(b) => b.spans_mut(&mut |s| *s = Z),
        Item::PddlMap(b) => b.spans_mut(&mut |s| *s = Z),
    }
}

fn norm_num(n: &mut Option<Number>) {
    if let Some(n) = n {
        n.span = Z;
    }
}

fn norm_value(v: &mut Value) {
    v.span = Z;
    match &mut v.kind {
        ValueKind::Ident(n) => n.span = Z,
        ValueKind::Number(n) => n.span = Z,
        ValueKind::Str(_) | ValueKind::Error => {}
        ValueKind::List { tag, items } => {
            if let Some(t) = tag {
                t.span = Z;
            }
            items.iter_mut().for_each(norm_value);
        }
    }
}

fn norm_block(b: &mut Block) {
    b.span = Z;
    for s in &mut b.stmts {
        s.span = Z;
        match &mut s.kind {
            StmtKind::Call(c) => {
                c.span = Z;
                c.args_span = Z;
                c.name.span = Z;
                if let Some(l) = &mut c.label {
                    l.span = Z;
                }
                c.args.iter_mut().for_each(norm_value);
            }
            StmtKind::While { keyword, cond, body } => {
                *keyword = Z;
                norm_block(cond);
                norm_block(body);
            }
            StmtKind::If { keyword, cond, then, otherwise, else_written_then } => {
                *keyword = Z;
                *else_written_then = None;
                norm_block(cond);
                norm_block(then);
                if let Some(o) = otherwise {
                    norm_block(o);
                }
            }
            StmtKind::Parallel { keyword, branches, ops } => {
                *keyword = Z;
                branches.iter_mut().for_each(norm_block);
                ops.iter_mut().for_each(|(_, s)| *s = Z);
            }
            StmtKind::Try { keyword, body, catch } => {
                *keyword = Z;
                norm_block(body);
                norm_block(catch);
            }
            StmtKind::Not { keyword, body } => {
                *keyword = Z;
                norm_block(body);
            }
            StmtKind::Monitor { keyword, body, handlers } => {
                *keyword = Z;
                norm_block(body);
                for h in handlers {
                    h.keyword_span = Z;
                    h.span = Z;
                    norm_block(&mut h.condition);
                    norm_block(&mut h.action);
                }
            }
            StmtKind::Error => {}
        }
    }
}

// ---------------------------------------------------------------------------
// The printer.

/// How a token behaves when a `// ...` comment waits for the end of its line.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Class {
    /// Breaks the line: the comment is written, the token continues on the
    /// next line one level deeper.
    Normal,
    /// `;`, `,`, `)`, `]`, `{`, `}`, `do`: written before the comment.
    Closer,
    /// A keyword after a block's `}` (`else`, `and`, `or`, `catch`,
    /// `condition`, `while_condition`): breaks the line, and continues at the
    /// same level.
    Keyword,
}

/// A comment and what the formatter needs to know about its surroundings.
struct Cmt {
    kind: CommentKind,
    text: String,
    start: usize,
    /// A blank line separates it from what precedes it.
    blank_before: bool,
    /// Nothing follows it on its line.
    newline_after: bool,
}

struct Printer<'a> {
    src: &'a str,
    toks: Vec<(Token<'a>, Span)>,
    comments: Vec<Cmt>,
    /// The first comment not written yet (comments are written in order).
    next: usize,
    lines: Vec<String>,
    /// The current line, without its indentation.
    line: String,
    line_indent: usize,
    indent: usize,
    /// The current line continues a line broken after a `// ...` comment.
    cont: bool,
    line_has_token: bool,
    pending_space: bool,
    /// A `// ...` comment to write at the end of the current line.
    deferred: Option<String>,
    /// The end of the furthest source token written.
    last_end: usize,
    last_was_opener: bool,
    /// The last finished line ends with an opening `{` or `(`.
    opener_line: bool,
}

fn blank_before(src: &str, pos: usize) -> bool {
    src[..pos].chars().rev().take_while(|c| c.is_whitespace()).filter(|&c| c == '\n').count() >= 2
}

fn newline_after(src: &str, pos: usize) -> bool {
    match src[pos..].chars().find(|&c| !c.is_whitespace() || c == '\n') {
        None | Some('\n') => true,
        Some(_) => false,
    }
}

impl<'a> Printer<'a> {
    fn new(src: &'a str, parse: &Parse) -> Self {
        let toks = lex(src).tokens;
        let comments = parse
            .comments
            .iter()
            .map(|c| Cmt {
                kind: c.kind,
                text: comment_text(src, c.kind, c.span),
                start: c.span.start as usize,
                blank_before: blank_before(src, c.span.start as usize),
                newline_after: c.kind == CommentKind::Line || newline_after(src, c.span.end as usize),
            })
            .collect();
        Printer {
            src,
            toks,
            comments,
            next: 0,
            lines: Vec::new(),
            line: String::new(),
            line_indent: 0,
            indent: 0,
            cont: false,
            line_has_token: false,
            pending_space: false,
            deferred: None,
            last_end: 0,
            last_was_opener: false,
            opener_line: false,
        }
    }

    // --- Source positions -------------------------------------------------

    /// Index of the first token starting at or after `pos`.
    fn tok_index(&self, pos: usize) -> usize {
        self.toks.partition_point(|(_, s)| (s.start as usize) < pos)
    }

    /// The first token at or after `from` that satisfies `pred`.
    fn find(&self, from: usize, pred: impl Fn(&Token<'_>) -> bool) -> Option<Span> {
        self.toks[self.tok_index(from)..].iter().find(|(t, _)| pred(t)).map(|(_, s)| *s)
    }

    fn find_tok(&self, from: usize, tok: Token<'static>) -> Option<Span> {
        self.find(from, |t| *t == tok)
    }

    /// The token right after the one starting at or after `pos`, offset by `delta`.
    fn tok_rel(&self, pos: usize, delta: isize) -> Option<(Token<'a>, Span)> {
        let i = self.tok_index(pos) as isize + delta;
        usize::try_from(i).ok().and_then(|i| self.toks.get(i)).copied()
    }

    /// The token that starts at or after `pos`.
    fn tok_at(&self, pos: usize) -> Option<Token<'a>> {
        self.toks.get(self.tok_index(pos)).map(|(t, _)| *t)
    }

    /// Where comments on the line of the last written token may end: the
    /// first token after it that the formatter may have dropped (or written
    /// again at the end of the line) does not count.
    fn same_line_limit(&self) -> usize {
        self.toks[self.tok_index(self.last_end)..]
            .iter()
            .find(|(t, _)| !matches!(t, Token::Semi | Token::Comma | Token::Kw(Kw::Then) | Token::Kw(Kw::Do)))
            .map_or(self.src.len() + 1, |(_, s)| s.start as usize)
    }

    // --- Writing ----------------------------------------------------------

    fn write(&mut self, text: &str, space: bool) {
        if self.line.is_empty() {
            self.line_indent = self.indent + usize::from(self.cont);
        } else if space || self.pending_space {
            self.line.push(' ');
        }
        self.pending_space = false;
        self.line.push_str(text);
    }

    /// Ends the current line (with the comment waiting for its end).
    fn end_line(&mut self) {
        if let Some(c) = self.deferred.take() {
            self.write(&c, true);
            self.last_was_opener = false;
        }
        let mut l = INDENT.repeat(self.line_indent);
        l.push_str(self.line.trim_end());
        self.lines.push(l);
        self.line.clear();
        self.pending_space = false;
        self.line_has_token = false;
        self.opener_line = self.last_was_opener;
        self.last_was_opener = false;
    }

    /// Breaks the line after a waiting `// ...` comment.
    fn break_line(&mut self, class: Class) {
        let had_token = self.line_has_token;
        self.end_line();
        self.cont = class != Class::Keyword && (self.cont || had_token);
    }

    /// Goes to the start of a line (after the comments left on this one).
    fn newline(&mut self) {
        if !self.line.is_empty() {
            self.flush_same_line();
            if !self.line.is_empty() || self.deferred.is_some() {
                self.end_line();
            }
        }
        self.cont = false;
    }

    /// A blank line, unless at the start of the file, after another blank
    /// line or after an opening delimiter.
    fn blank(&mut self) {
        if !self.line.is_empty() {
            return;
        }
        if self.lines.last().is_some_and(|l| !l.is_empty()) && !self.opener_line {
            self.lines.push(String::new());
        }
    }

    /// Writes the comments that follow the last token on its source line.
    fn flush_same_line(&mut self) {
        let limit = self.same_line_limit();
        while let Some(c) = self.comments.get(self.next) {
            // After a `// ...` comment, the others start the next lines.
            if self.deferred.is_some()
                || c.start >= limit
                || c.start < self.last_end
                || self.src[self.last_end..c.start].contains('\n')
            {
                break;
            }
            self.next += 1;
            self.comment(self.next - 1, Class::Keyword);
        }
    }

    /// Writes the comments that start before `pos`.
    fn flush_before(&mut self, pos: usize) {
        while self.comments.get(self.next).is_some_and(|c| c.start < pos) {
            self.next += 1;
            self.comment(self.next - 1, Class::Normal);
        }
    }

    /// Writes comment `i`; if a `// ...` comment waits for the end of the
    /// line, the line is broken first as before a token of class `class`.
    fn comment(&mut self, i: usize, class: Class) {
        if self.deferred.is_some() {
            self.break_line(class);
        }
        let c = &self.comments[i];
        let (kind, blank, nl_after) = (c.kind, c.blank_before, c.newline_after);
        let text = std::mem::take(&mut self.comments[i].text);
        if self.line.is_empty() {
            if blank && !self.cont {
                self.blank();
            }
            self.write(&text, false);
            self.last_was_opener = false;
            if nl_after {
                self.end_line();
            } else {
                self.pending_space = true;
            }
        } else if kind == CommentKind::Block {
            self.write(&text, true);
            self.last_was_opener = false;
            self.pending_space = true;
        } else {
            self.deferred = Some(text);
        }
    }

    /// Writes one token; `span` is where it is in the source, if it is there.
    fn tok(&mut self, text: &str, span: Option<Span>, class: Class, space: bool) {
        if let Some(s) = span {
            self.flush_before(s.start as usize);
        }
        if self.deferred.is_some() && class != Class::Closer {
            self.break_line(class);
        }
        self.write(text, space);
        self.line_has_token = true;
        self.last_was_opener = text == "{" || text == "(";
        if let Some(s) = span {
            self.last_end = self.last_end.max(s.end as usize);
        }
    }

    fn name(&mut self, n: &Name, space: bool) {
        self.tok(&n.text, Some(n.span), Class::Normal, space);
    }

    fn num(&mut self, n: &Number, space: bool) {
        self.tok(&n.text, Some(n.span), Class::Normal, space);
    }

    /// Starts a line-level element (definition, statement, ...) at `pos`.
    fn line_element(&mut self, pos: usize) {
        self.newline();
        self.flush_before(pos);
        if blank_before(self.src, pos) {
            self.blank();
        }
    }

    /// `{` at `open`; the caller writes the lines of the block.
    fn open(&mut self, open: Option<Span>) {
        self.tok("{", open, Class::Closer, true);
        self.indent += 1;
    }

    /// Closes a block opened with [`Printer::open`]: `}` on its own line, or
    /// `{ }` when the block is empty and holds no comment.
    fn close(&mut self, close: Option<Span>, empty: bool) {
        let pos = close.map_or(self.last_end, |s| s.start as usize);
        let has_comment = self.comments.get(self.next).is_some_and(|c| c.start < pos);
        if empty && !has_comment && self.deferred.is_none() {
            self.indent -= 1;
            self.tok("}", close, Class::Closer, true);
            return;
        }
        self.newline();
        self.flush_before(pos);
        self.newline();
        self.indent -= 1;
        self.tok("}", close, Class::Closer, false);
    }

    fn span1(pos: usize) -> Option<Span> {
        Some(Span::new(pos, pos + 1))
    }

    // --- Items -------------------------------------------------------------

    fn file(mut self, file: &SourceFile) -> String {
        for (i, item) in file.items.iter().enumerate() {
            let after_import = i > 0 && matches!(file.items[i - 1], Item::Import(_));
            let force_blank = i > 0 && !(after_import && matches!(item, Item::Import(_)));
            self.newline();
            if force_blank {
                self.blank();
            }
            self.line_element(item.span().start as usize);
            self.item(item);
        }
        self.newline();
        self.flush_before(usize::MAX);
        self.newline();
        let mut out = self.lines.join("\n");
        if !out.is_empty() {
            out.push('\n');
        }
        out
    }

    fn keyword_at(&mut self, text: &str, pos: usize) {
        let span = self.toks.get(self.tok_index(pos)).map(|(_, s)| *s);
        self.tok(text, span, Class::Normal, true);
    }

    fn item(&mut self, item: &Item) {
        match item {
            Item::Import(i) => {
                self.keyword_at("import", i.span.start as usize);
                let path = &self.src[i.path_span.range()];
                self.tok(path, Some(i.path_span), Class::Normal, true);
                let semi = self.find_tok(i.path_span.end as usize, Token::Semi);
                self.tok(";", semi, Class::Closer, false);
            }
            Item::Actions(a) => {
                self.keyword_at("actions", a.span.start as usize);
                self.open(self.find_tok(a.span.start as usize, Token::LBrace));
                for d in &a.actions {
                    self.line_element(d.span.start as usize);
                    self.action(d);
                }
                self.close(Self::span1(a.span.end as usize - 1), a.actions.is_empty());
            }
            Item::Events(e) => {
                self.keyword_at("events", e.span.start as usize);
                self.open(self.find_tok(e.span.start as usize, Token::LBrace));
                for n in &e.events {
                    self.line_element(n.span.start as usize);
                    self.name(n, true);
                    let semi = self.find_tok(n.span.end as usize, Token::Semi);
                    self.tok(";", semi, Class::Closer, false);
                }
                self.close(Self::span1(e.span.end as usize - 1), e.events.is_empty());
            }
            Item::Patterns(p) => {
                self.keyword_at("pattern", p.span.start as usize);
                self.open(self.find_tok(p.span.start as usize, Token::LBrace));
                for pat in &p.patterns {
                    self.line_element(pat.span.start as usize);
                    self.pattern(pat);
                }
                self.close(Self::span1(p.span.end as usize - 1), p.patterns.is_empty());
            }
            Item::Tasks(t) => {
                self.keyword_at("tasks", t.span.start as usize);
                self.open(self.find_tok(t.span.start as usize, Token::LBrace));
                for task in &t.tasks {
                    self.line_element(task.span.start as usize);
                    self.task(task);
                }
                self.close(Self::span1(t.span.end as usize - 1), t.tasks.is_empty());
            }
            Item::Mission(m) => self.mission(m),
            Item::Constraints(c) => {
                self.keyword_at("constraints", c.span.start as usize);
                self.open(self.find_tok(c.span.start as usize, Token::LBrace));
                for k in &c.constraints {
                    self.line_element(k.span.start as usize);
                    self.constraint(k);
                }
                self.close(Self::span1(c.span.end as usize - 1), c.constraints.is_empty());
            }
            Item::Planning(b) => self.planning(b),
            Item::PddlMap(b) => self.pddl_map(b),
        }
    }

    /// `c:` or `v:` before the value starting at `pos`.
    fn marker(&mut self, text: &str, pos: usize, space: bool) {
        let m = self.tok_rel(pos, -2).map(|(_, s)| s);
        let colon = self.tok_rel(pos, -1).map(|(_, s)| s);
        self.tok(text, m, Class::Normal, space);
        self.tok(":", colon, Class::Normal, false);
    }

    fn action(&mut self, d: &ActionDef) {
        self.name(&d.name, true);
        let eq = self.find_tok(d.name.span.end as usize, Token::Eq);
        self.tok("=", eq, Class::Normal, true);
        self.name(&d.primitive, true);
        let open = self.find_tok(d.primitive.span.end as usize, Token::LParen);
        self.tok("(", open, Class::Normal, false);
        // The command comes first; commas are located when that is also the
        // order of the source.
        let in_order = d.command.as_ref().is_none_or(|c| d.params.iter().all(|p| p.span.start > c.span.start));
        let mut prev_end = None;
        if let Some(c) = &d.command {
            self.marker("c", c.span.start as usize, true);
            self.name(c, true);
            prev_end = Some(c.span.end as usize);
        }
        for p in &d.params {
            if let Some(end) = prev_end {
                let comma = if in_order { self.find_tok(end, Token::Comma) } else { None };
                self.tok(",", comma, Class::Closer, false);
            }
            self.marker("v", p.span.start as usize, true);
            self.value(p, true);
            prev_end = Some(p.span.end as usize);
        }
        self.tok(")", Self::span1(d.span.end as usize - 1), Class::Closer, true);
        let semi = self.find_tok(d.span.end as usize, Token::Semi);
        self.tok(";", semi, Class::Closer, false);
    }

    fn value(&mut self, v: &Value, space: bool) {
        match &v.kind {
            ValueKind::Ident(n) => self.name(n, space),
            ValueKind::Number(n) => self.num(n, space),
            ValueKind::Str(_) => {
                let text = &self.src[v.span.range()];
                self.tok(text, Some(v.span), Class::Normal, space);
            }
            ValueKind::List { tag, items } => {
                let from = match tag {
                    Some(t) => {
                        self.name(t, space);
                        t.span.end as usize
                    }
                    None => v.span.start as usize,
                };
                let open = self.find_tok(from, Token::LBracket);
                self.tok("[", open, Class::Normal, tag.is_none() && space);
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        let comma = self.find_tok(items[i - 1].span.end as usize, Token::Comma);
                        self.tok(",", comma, Class::Closer, false);
                    }
                    self.value(item, i > 0);
                }
                self.tok("]", Self::span1(v.span.end as usize - 1), Class::Closer, false);
            }
            ValueKind::Error => {}
        }
    }

    /// `name.interface`.
    fn interface(&mut self, i: &Option<Number>) {
        if let Some(i) = i {
            let dot = self.tok_rel(i.span.start as usize, -1).map(|(_, s)| s);
            self.tok(".", dot, Class::Normal, false);
            self.num(i, false);
        }
    }

    /// `(x)` around the token at `inner`, written by `f`.
    fn parens(&mut self, inner: Span, space: bool, f: impl FnOnce(&mut Self)) {
        let open = self.tok_rel(inner.start as usize, -1).map(|(_, s)| s);
        let close = self.tok_rel(inner.start as usize, 1).map(|(_, s)| s);
        self.tok("(", open, Class::Normal, space);
        f(self);
        self.tok(")", close, Class::Closer, false);
    }

    fn pattern(&mut self, pat: &Pattern) {
        self.name(&pat.name, true);
        match &pat.body {
            PatternBody::File { path, path_span } => {
                let colon = self.find_tok(pat.name.span.end as usize, Token::Colon);
                self.tok(":", colon, Class::Normal, true);
                let written = &self.src[path_span.range()];
                let text = if written.starts_with('"') { written.to_string() } else { path.clone() };
                self.tok(&text, Some(*path_span), Class::Normal, true);
                let semi = self.find_tok(path_span.end as usize, Token::Semi);
                self.tok(";", semi, Class::Closer, false);
            }
            PatternBody::Net(net) => {
                let open = self.find_tok(pat.name.span.end as usize, Token::LBrace);
                self.open(open);
                let mut from = open.map_or(pat.name.span.end as usize, |s| s.end as usize);
                // places
                from = self.section("places", Kw::Places, from, &net.places, |p, d| {
                    p.name(&d.name, true);
                    p.interface(&d.interface);
                    if let Some(t) = &d.tokens {
                        p.parens(t.span, false, |p| p.num(t, false));
                    }
                    d.span
                });
                from = self.section("transitions", Kw::Transitions, from, &net.transitions, |p, d| {
                    p.name(&d.name, true);
                    p.interface(&d.interface);
                    match &d.delay {
                        Some(Delay::Fixed(n)) => p.parens(n.span, false, |p| p.num(n, false)),
                        Some(Delay::Param(n)) => p.parens(n.span, false, |p| p.name(n, false)),
                        None => {}
                    }
                    d.span
                });
                self.section("arcs", Kw::Arcs, from, &net.arcs, |p, d| {
                    p.name(&d.source.name, true);
                    p.interface(&d.source.interface);
                    let from = d.source.interface.as_ref().map_or(d.source.name.span.end, |i| i.span.end);
                    let arrow = p.find_tok(from as usize, Token::Arrow);
                    p.tok("->", arrow, Class::Normal, true);
                    p.name(&d.target.name, true);
                    p.interface(&d.target.interface);
                    if let Some(w) = &d.weight {
                        p.parens(w.span, true, |p| p.num(w, false));
                    }
                    d.span
                });
                self.close(Self::span1(pat.span.end as usize - 1), false);
            }
        }
    }

    /// One section of a pattern net; returns the end of its `}`.
    fn section<T>(
        &mut self,
        text: &str,
        kw: Kw,
        from: usize,
        defs: &[T],
        mut def: impl FnMut(&mut Self, &T) -> Span,
    ) -> usize {
        let k = self.find_tok(from, Token::Kw(kw));
        let k_pos = k.map_or(from, |s| s.start as usize);
        self.line_element(k_pos);
        self.tok(text, k, Class::Normal, true);
        let open = self.find_tok(k_pos, Token::LBrace);
        self.open(open);
        for d in defs {
            // The definition's first token is its name.
            let start = self.toks.get(self.tok_index(self.last_end)).map_or(self.last_end, |(_, s)| s.start as usize);
            self.line_element(start);
            let span = def(self, d);
            let semi = self.find_tok(span.end as usize, Token::Semi);
            self.tok(";", semi, Class::Closer, false);
        }
        let close = self.find_tok(self.last_end, Token::RBrace);
        self.close(close, defs.is_empty());
        close.map_or(self.last_end, |s| s.end as usize)
    }

    fn task(&mut self, t: &TaskDef) {
        self.name(&t.name, true);
        let open = self.find_tok(t.name.span.end as usize, Token::LParen);
        self.tok("(", open, Class::Normal, false);
        let end = self.names(&t.params, open.map_or(t.name.span.end as usize, |s| s.end as usize));
        let close = self.find_tok(end, Token::RParen);
        self.tok(")", close, Class::Closer, !t.params.is_empty());
        let mut from = close.map_or(end, |s| s.end as usize);
        if let Some(p) = &t.pattern {
            let colon = self.find_tok(from, Token::Colon);
            self.tok(":", colon, Class::Normal, false);
            self.name(p, true);
            from = p.span.end as usize;
        }
        self.open(self.find_tok(from, Token::LBrace));
        for b in &t.bindings {
            self.line_element(b.span.start as usize);
            let kind = if b.kind == BindingKind::Action { "a" } else { "e" };
            self.keyword_at(kind, b.span.start as usize);
            let colon = self.find_tok(b.span.start as usize + 1, Token::Colon);
            self.tok(":", colon, Class::Normal, false);
            self.name(&b.target, true);
            let arrow = self.find_tok(b.target.span.end as usize, Token::Arrow);
            self.tok("->", arrow, Class::Normal, true);
            self.names(&b.transitions, arrow.map_or(b.target.span.end as usize, |s| s.end as usize));
            let semi = self.find_tok(b.span.end as usize, Token::Semi);
            self.tok(";", semi, Class::Closer, false);
        }
        self.close(Self::span1(t.span.end as usize - 1), t.bindings.is_empty());
    }

    /// `a, b, c` (each after a space); returns the end of the last one.
    fn names(&mut self, names: &[Name], mut end: usize) -> usize {
        for (i, n) in names.iter().enumerate() {
            if i > 0 {
                let comma = self.find_tok(end, Token::Comma);
                self.tok(",", comma, Class::Closer, false);
            }
            self.name(n, true);
            end = n.span.end as usize;
        }
        end
    }

    /// `( a, b )` or `()`, starting the search for `(` at `from`.
    fn param_list(&mut self, params: &[Name], from: usize) {
        let open = self.find_tok(from, Token::LParen);
        self.tok("(", open, Class::Normal, false);
        let end = self.names(params, open.map_or(from, |s| s.end as usize));
        let close = self.find_tok(end, Token::RParen);
        self.tok(")", close, Class::Closer, !params.is_empty());
    }

    fn mission(&mut self, m: &Mission) {
        let kw = match m.kind {
            MissionKind::Mission => "mission",
            MissionKind::PlanOp => "mcl_plan_op",
        };
        self.tok(kw, Some(m.keyword_span), Class::Normal, true);
        let after_kw = m.keyword_span.end as usize;
        if let Some(n) = &m.name {
            let named = m.kind == MissionKind::Mission && self.tok_at(after_kw) == Some(Token::Colon);
            if named {
                let colon = self.find_tok(after_kw, Token::Colon);
                self.tok(":", colon, Class::Normal, true);
                self.name(n, true);
                if let Some((id, at)) = &m.placement {
                    let open = self.find_tok(n.span.end as usize, Token::LBracket);
                    self.tok("[", open, Class::Normal, true);
                    self.name(id, true);
                    let at_kw = self.tok_rel(at.span.start as usize, -1).map(|(_, s)| s);
                    self.tok("at", at_kw, Class::Normal, true);
                    self.num(at, true);
                    let close = self.tok_rel(at.span.start as usize, 1).map(|(_, s)| s);
                    self.tok("]", close, Class::Closer, true);
                }
            } else {
                self.name(n, true);
                self.param_list(&m.params, n.span.end as usize);
            }
        }
        // The body's `{` is the token before its first statement.
        let first = m.body.stmts.first().map_or(m.body.span.start as usize, |s| s.span.start as usize);
        let open = self.tok_rel(first, -1).filter(|(t, _)| *t == Token::LBrace).map(|(_, s)| s);
        self.open(open);
        self.stmt_lines(&m.body);
        self.close(Self::span1(m.span.end as usize - 1), false);
    }

    fn constraint(&mut self, k: &Constraint) {
        self.tok(k.kind.as_str(), Some(k.keyword_span), Class::Normal, true);
        let open = self.find_tok(k.keyword_span.end as usize, Token::LBrace);
        self.tok("{", open, Class::Normal, true);
        let mut end = open.map_or(k.keyword_span.end as usize, |s| s.end as usize);
        for (i, r) in k.refs.iter().enumerate() {
            if i > 0 {
                let comma = self.find_tok(end, Token::Comma);
                self.tok(",", comma, Class::Closer, false);
            }
            match &r.mission {
                Some(m) => {
                    self.name(m, true);
                    let colon = self.find_tok(m.span.end as usize, Token::Colon);
                    self.tok(":", colon, Class::Normal, false);
                    self.name(&r.label, false);
                }
                None => self.name(&r.label, true),
            }
            end = r.span.end as usize;
        }
        let close = self.find_tok(end, Token::RBrace);
        self.tok("}", close, Class::Closer, true);
        if let Some(b) = &k.bound {
            let eq = self.find_tok(close.map_or(end, |s| s.end as usize), Token::Eq);
            self.tok("=", eq, Class::Normal, true);
            self.num(b, true);
        }
    }

    // --- Statements --------------------------------------------------------

    /// The statements of a block, one per line, `;` at the end of all but the last.
    fn stmt_lines(&mut self, b: &Block) {
        let n = b.stmts.len();
        for (i, s) in b.stmts.iter().enumerate() {
            self.line_element(s.span.start as usize);
            self.stmt(s);
            if i + 1 < n {
                let semi = self.find_tok(s.span.end as usize, Token::Semi);
                self.tok(";", semi, Class::Closer, true);
            }
        }
    }

    /// A block written between braces in the source (its span includes them).
    fn braced(&mut self, b: &Block) {
        self.open(Self::span1(b.span.start as usize));
        self.stmt_lines(b);
        self.close(Self::span1(b.span.end as usize - 1), false);
    }

    /// A condition or the body of `not`, written `( ... )`, whatever its
    /// form in the source: `( A )`, `{ A }` or a bare `A` before `then`/`do`.
    /// `after` is the end of the keyword that precedes it.
    fn cond(&mut self, after: usize, b: &Block) {
        let (open, close) = match self.tok_rel(after, 0) {
            Some((Token::LParen, s)) => (Some(s), self.find_tok(b.span.end as usize, Token::RParen)),
            Some((Token::LBrace, s)) if s.start == b.span.start => (Some(s), Self::span1(b.span.end as usize - 1)),
            _ => (None, None),
        };
        self.tok("(", open, Class::Normal, true);
        if b.stmts.iter().all(simple) {
            let n = b.stmts.len();
            for (i, s) in b.stmts.iter().enumerate() {
                self.stmt(s);
                if i + 1 < n {
                    let semi = self.find_tok(s.span.end as usize, Token::Semi);
                    self.tok(";", semi, Class::Closer, true);
                }
            }
            self.tok(")", close, Class::Closer, true);
        } else {
            self.indent += 1;
            self.stmt_lines(b);
            let pos = close.map_or(self.last_end, |s| s.start as usize);
            self.newline();
            self.flush_before(pos);
            self.newline();
            self.indent -= 1;
            self.tok(")", close, Class::Closer, false);
        }
    }

    fn stmt(&mut self, s: &Stmt) {
        match &s.kind {
            StmtKind::Call(c) => self.call(c),
            StmtKind::Not { keyword, body } => {
                self.tok("not", Some(*keyword), Class::Normal, true);
                self.cond(keyword.end as usize, body);
            }
            StmtKind::If { keyword, cond, then, otherwise, else_written_then } => {
                self.tok("if", Some(*keyword), Class::Normal, true);
                self.cond(keyword.end as usize, cond);
                self.braced(then);
                if let Some(o) = otherwise {
                    let kw = else_written_then.or_else(|| self.find_tok(then.span.end as usize, Token::Kw(Kw::Else)));
                    self.tok("else", kw, Class::Keyword, true);
                    self.braced(o);
                }
            }
            StmtKind::While { keyword, cond, body } => {
                self.tok("while", Some(*keyword), Class::Normal, true);
                self.cond(keyword.end as usize, cond);
                self.braced(body);
            }
            StmtKind::Try { keyword, body, catch } => {
                self.tok("try", Some(*keyword), Class::Normal, true);
                self.braced(body);
                let kw = self.find_tok(body.span.end as usize, Token::Kw(Kw::Catch));
                self.tok("catch", kw, Class::Keyword, true);
                self.braced(catch);
            }
            StmtKind::Parallel { keyword, branches, ops } => {
                self.tok("parallel", Some(*keyword), Class::Normal, true);
                for (i, b) in branches.iter().enumerate() {
                    if i > 0 {
                        let (op, span) = ops[i - 1];
                        let text = if op == ParallelOp::And { "and" } else { "or" };
                        self.tok(text, Some(span), Class::Keyword, true);
                    }
                    self.braced(b);
                }
            }
            StmtKind::Monitor { keyword, body, handlers } => {
                self.tok("monitor", Some(*keyword), Class::Normal, true);
                self.braced(body);
                for h in handlers {
                    let text = match h.kind {
                        MonitorKind::Condition => "condition",
                        MonitorKind::WhileCondition => "while_condition",
                    };
                    self.tok(text, Some(h.keyword_span), Class::Keyword, true);
                    self.cond(h.keyword_span.end as usize, &h.condition);
                    let kw = self.find_tok(h.condition.span.end as usize, Token::Kw(Kw::Do));
                    self.tok("do", kw, Class::Closer, true);
                    self.braced(&h.action);
                }
            }
            StmtKind::Error => {}
        }
    }

    fn call(&mut self, c: &Call) {
        self.name(&c.name, true);
        self.tok("(", Self::span1(c.args_span.start as usize), Class::Normal, false);
        for (i, a) in c.args.iter().enumerate() {
            if i > 0 {
                let comma = self.find_tok(c.args[i - 1].span.end as usize, Token::Comma);
                self.tok(",", comma, Class::Closer, false);
            }
            self.value(a, true);
        }
        self.tok(")", Self::span1(c.args_span.end as usize - 1), Class::Closer, !c.args.is_empty());
        if let Some(l) = &c.label {
            let colon = self.find_tok(c.args_span.end as usize, Token::Colon);
            self.tok(":", colon, Class::Normal, true);
            self.name(l, true);
        }
    }
}

// --- Planning blocks (docs/planning.md) -------------------------------------
//
// `planning { ... }`: one definition per line; the attribute list of a type,
// the values of an entity and the facts and expressions of an operator's
// parts on one line (`precond { v in l1; }`); an operator's parts one per
// line; the entries of `initial` and `goal` one per line. `pddl_map { ... }`:
// one mapping per line.
impl Printer<'_> {
    /// The last `tok` in `[from, end)`.
    fn last_tok_in(&self, from: usize, end: usize, tok: Token<'static>) -> Option<Span> {
        let (a, b) = (self.tok_index(from), self.tok_index(end));
        self.toks[a..b].iter().rev().find(|(t, _)| *t == tok).map(|(_, s)| *s)
    }

    /// The `tok` at `pos` (the first token there), if it is one.
    fn tok_if(&self, pos: usize, tok: Token<'static>) -> Option<Span> {
        self.toks.get(self.tok_index(pos)).filter(|(t, _)| *t == tok).map(|(_, s)| *s)
    }

    fn semi_after(&mut self, pos: usize) {
        let semi = self.tok_if(pos, Token::Semi);
        self.tok(";", semi, Class::Closer, false);
    }

    /// `{ a; b; }` on one line: each item written by `f`, its end given by `end_of`.
    fn inline_list<T>(
        &mut self,
        from: usize,
        end: usize,
        items: &[T],
        end_of: impl Fn(&T) -> usize,
        mut f: impl FnMut(&mut Self, &T),
    ) {
        let open = self.tok_if(from, Token::LBrace);
        self.tok("{", open, Class::Closer, true);
        for x in items {
            f(self, x);
            self.semi_after(end_of(x));
        }
        let close = self.last_tok_in(from, end, Token::RBrace);
        self.tok("}", close, Class::Closer, true);
    }

    fn plan_fact(&mut self, x: &PlanFact) {
        if let Some(n) = x.negated {
            self.tok("not", Some(n), Class::Normal, true);
        }
        self.name(&x.subject, true);
        self.name(&x.relation, true);
        if let Some(o) = &x.object {
            self.name(o, true);
        }
    }

    fn plan_operand(&mut self, o: &PlanOperand, space: bool) {
        match &o.kind {
            OperandKind::Name(n) => self.name(n, space),
            OperandKind::Attr(a, b) => {
                self.name(a, space);
                let dot = self.tok_if(a.span.end as usize, Token::Dot);
                self.tok(".", dot, Class::Normal, false);
                self.name(b, false);
            }
            OperandKind::Function(n, args) => {
                self.name(n, space);
                self.param_list(args, n.span.end as usize);
            }
            OperandKind::Literal(v) => self.value(v, space),
        }
    }

    fn plan_call(&mut self, c: &PlanCall) {
        self.name(&c.name, true);
        let open = self.tok_if(c.name.span.end as usize, Token::LParen);
        self.tok("(", open, Class::Normal, false);
        for (i, a) in c.args.iter().enumerate() {
            if i > 0 {
                let comma = self.tok_if(c.args[i - 1].span.end as usize, Token::Comma);
                self.tok(",", comma, Class::Closer, false);
            }
            self.plan_operand(a, true);
        }
        let close = self.last_tok_in(c.name.span.end as usize, c.span.end as usize, Token::RParen);
        self.tok(")", close, Class::Closer, !c.args.is_empty());
    }

    fn planning(&mut self, b: &PlanningBlock) {
        self.tok("planning", Some(b.keyword_span), Class::Normal, true);
        self.open(self.tok_if(b.keyword_span.end as usize, Token::LBrace));
        for d in &b.defs {
            self.line_element(d.span().start as usize);
            self.plan_def(d);
        }
        let close = self.last_tok_in(b.keyword_span.end as usize, b.span.end as usize, Token::RBrace);
        self.close(close, b.defs.is_empty());
    }

    fn plan_def(&mut self, d: &PlanDef) {
        match d {
            PlanDef::Type(t) => {
                self.tok("type", Some(t.keyword_span), Class::Normal, true);
                self.name(&t.name, true);
                let mut end = t.name.span.end as usize;
                if let Some(p) = &t.parent {
                    let colon = self.tok_if(end, Token::Colon);
                    self.tok(":", colon, Class::Normal, true);
                    self.name(p, true);
                    end = p.span.end as usize;
                }
                if t.attrs.is_empty() {
                    self.semi_after(end);
                } else {
                    self.inline_list(
                        end,
                        t.span.end as usize,
                        &t.attrs,
                        |a| a.span.end as usize,
                        |p, a| p.name(a, true),
                    );
                }
            }
            PlanDef::Entity(x) => {
                self.tok("entity", Some(x.keyword_span), Class::Normal, true);
                self.name(&x.ty, true);
                self.name(&x.name, true);
                let end = x.name.span.end as usize;
                if x.values.is_empty() {
                    self.semi_after(end);
                } else {
                    self.inline_list(
                        end,
                        x.span.end as usize,
                        &x.values,
                        |v| v.span.end as usize,
                        |p, v| {
                            p.name(&v.name, true);
                            let eq = p.tok_if(v.name.span.end as usize, Token::Eq);
                            p.tok("=", eq, Class::Normal, true);
                            p.value(&v.value, true);
                        },
                    );
                }
            }
            PlanDef::Function(x) => {
                self.tok("function", Some(x.keyword_span), Class::Normal, true);
                self.name(&x.name, true);
                self.param_list(&x.params, x.name.span.end as usize);
                let close = self.last_tok_in(x.name.span.end as usize, x.span.end as usize, Token::RParen);
                self.semi_after(close.map_or(x.span.end as usize, |s| s.end as usize));
            }
            PlanDef::Operator(o) => {
                self.tok("operator", Some(o.keyword_span), Class::Normal, true);
                self.name(&o.name, true);
                let open = self.tok_if(o.name.span.end as usize, Token::LParen);
                self.tok("(", open, Class::Normal, false);
                let mut end = open.map_or(o.name.span.end as usize, |s| s.end as usize);
                for (i, p) in o.params.iter().enumerate() {
                    if i > 0 {
                        let comma = self.tok_if(end, Token::Comma);
                        self.tok(",", comma, Class::Closer, false);
                    }
                    self.name(&p.ty, true);
                    self.name(&p.name, true);
                    end = p.name.span.end as usize;
                }
                let close = self.find_tok(end, Token::RParen);
                self.tok(")", close, Class::Closer, !o.params.is_empty());
                let from = close.map_or(end, |s| s.end as usize);
                self.open(self.tok_if(from, Token::LBrace));
                for part in &o.parts {
                    self.line_element(part.span.start as usize);
                    self.op_part(part);
                }
                let close = self.last_tok_in(from, o.span.end as usize, Token::RBrace);
                self.close(close, o.parts.is_empty());
            }
            PlanDef::Facts(x) => {
                let kw = if x.goal { "goal" } else { "initial" };
                self.tok(kw, Some(x.keyword_span), Class::Normal, true);
                let from = x.keyword_span.end as usize;
                self.open(self.tok_if(from, Token::LBrace));
                // Facts and values in source order.
                let mut entries: Vec<(usize, Result<&PlanFact, &FunctionValue>)> =
                    x.facts.iter().map(|f| (f.span.start as usize, Ok(f))).collect();
                entries.extend(x.values.iter().map(|v| (v.span.start as usize, Err(v))));
                entries.sort_by_key(|e| e.0);
                for (start, e) in &entries {
                    self.line_element(*start);
                    match e {
                        Ok(f) => {
                            self.plan_fact(f);
                            self.semi_after(f.span.end as usize);
                        }
                        Err(v) => {
                            self.name(&v.name, true);
                            self.param_list(&v.args, v.name.span.end as usize);
                            let eq = self.find_tok(v.name.span.end as usize, Token::Eq);
                            self.tok("=", eq, Class::Normal, true);
                            self.value(&v.value, true);
                            self.semi_after(v.span.end as usize);
                        }
                    }
                }
                let close = self.last_tok_in(from, x.span.end as usize, Token::RBrace);
                self.close(close, entries.is_empty());
            }
        }
    }

    fn op_part(&mut self, part: &OpPart) {
        self.tok(part.kind.keyword(), Some(part.keyword_span), Class::Normal, true);
        let from = part.keyword_span.end as usize;
        let end = part.span.end as usize;
        match &part.kind {
            OpPartKind::Precond(v) | OpPartKind::Add(v) | OpPartKind::Del(v) => {
                self.inline_list(from, end, v, |f| f.span.end as usize, |p, f| p.plan_fact(f))
            }
            OpPartKind::Expression(v) => self.inline_list(
                from,
                end,
                v,
                |x| x.span.end as usize,
                |p, x| {
                    p.plan_operand(&x.left, true);
                    p.tok(&x.op, Some(x.op_span), Class::Normal, true);
                    p.plan_operand(&x.right, true);
                },
            ),
            OpPartKind::Cost(c) => {
                self.plan_operand(c, true);
                self.semi_after(c.span.end as usize);
            }
            OpPartKind::Mcl(c) => {
                self.plan_call(c);
                self.semi_after(c.span.end as usize);
            }
        }
    }

    fn pddl_map(&mut self, b: &PddlMapBlock) {
        self.tok("pddl_map", Some(b.keyword_span), Class::Normal, true);
        self.open(self.tok_if(b.keyword_span.end as usize, Token::LBrace));
        for m in &b.maps {
            self.line_element(m.span.start as usize);
            self.name(&m.action, true);
            self.param_list(&m.params, m.action.span.end as usize);
            let arrow = self.find_tok(m.action.span.end as usize, Token::Arrow);
            self.tok("->", arrow, Class::Normal, true);
            self.plan_call(&m.call);
            self.semi_after(m.call.span.end as usize);
        }
        let close = self.last_tok_in(b.keyword_span.end as usize, b.span.end as usize, Token::RBrace);
        self.close(close, b.maps.is_empty());
    }
}

/// A statement simple enough to be written inside a one-line condition.
fn simple(s: &Stmt) -> bool {
    match &s.kind {
        StmtKind::Call(_) => true,
        StmtKind::Not { body, .. } => body.stmts.iter().all(simple),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fmt(s: &str) -> String {
        format(s).unwrap_or_else(|e| panic!("{e:?}"))
    }

    #[test]
    fn canonical_spellings() {
        let src = "mission { if A() then { B() } then { C() } ; while D() do { E() } ; not { F() } }";
        assert_eq!(
            fmt(src),
            "mission {\n    if ( A() ) {\n        B()\n    } else {\n        C()\n    } ;\n    while ( D() ) {\n        E()\n    } ;\n    not ( F() )\n}\n"
        );
    }

    #[test]
    fn refuses_syntax_errors() {
        assert!(matches!(format("mission { A( }"), Err(FormatError::Syntax(_))));
    }

    #[test]
    fn empty_file() {
        assert_eq!(fmt(""), "");
        assert_eq!(fmt("  \n\n"), "");
        assert_eq!(fmt("// c\n"), "// c\n");
    }
}
