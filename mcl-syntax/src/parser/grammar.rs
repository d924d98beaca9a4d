//! Pass 2 of parsing: the chumsky grammar of the language, run on the
//! balanced token stream. It recovers at statement, definition and item
//! boundaries. The grammar is built once per thread ([`GRAMMAR`]) in two
//! instances: a quick one without error reporting and one with rich errors.
//! The planning blocks' grammar is in [`super::planning`].

use super::errors::rich_to_diagnostic;
use super::planning::{pddl_map_item, planning_item};
use crate::ast::*;
use crate::diag::{codes, Diagnostic};
use crate::lexer::{unescape, Kw, Token};
use crate::span::Span;
use chumsky::cache::{Cache, Cached};
use chumsky::error::EmptyErr;
use chumsky::input::{Input, MappedInput, ValueInput};
use chumsky::inspector::SimpleState;
use chumsky::label::LabelError;
use chumsky::prelude::*;

/// The grammar's input: the balanced tokens with their spans.
type In<'t, 's> = MappedInput<
    't,
    Token<'s>,
    SimpleSpan,
    &'t [(Token<'s>, SimpleSpan)],
    fn(&'t (Token<'s>, SimpleSpan)) -> (&'t Token<'s>, &'t SimpleSpan),
>;

/// The parser's extra types: its errors `R` (rich, or [`EmptyErr`] for the
/// quick pass), and its state, where the current item ends (`usize::MAX` for
/// a whole file): the keyword of the next item that follows is not parsed.
pub(super) type Ex<R> = extra::Full<R, SimpleState<usize>, ()>;

/// The errors the grammar can produce: [`Rich`] ones, or none at all
/// ([`EmptyErr`]: only whether an error happened).
pub(super) trait Fail<'t, I: Input<'t>>:
    chumsky::error::Error<'t, I> + LabelError<'t, I, &'static str> + 't
{
    /// An error with a message (see [`custom`]).
    fn custom(span: SimpleSpan, msg: String) -> Self;
}

impl<'t, 's: 't, I: Input<'t, Token = Token<'s>, Span = SimpleSpan>> Fail<'t, I> for Rich<'t, Token<'s>, SimpleSpan> {
    fn custom(span: SimpleSpan, msg: String) -> Self {
        Rich::custom(span, msg)
    }
}

impl<'t, I: Input<'t>> Fail<'t, I> for EmptyErr {
    fn custom(_: SimpleSpan, _: String) -> Self {
        EmptyErr::default()
    }
}

/// Runs the grammar on balanced `tokens` (`eoi`: where the input ends):
/// of one item when `item` (`limit` is where the item ends and the next
/// item's keyword, which is not parsed, starts), else of a whole file. With
/// `quick`, the quick pass runs first and its tree is kept when it finds no
/// error. Returns the tree, if any, and the syntax errors.
pub(super) fn run<'t>(
    tokens: &'t [(Token<'t>, SimpleSpan)],
    eoi: SimpleSpan,
    item: bool,
    limit: usize,
    quick: bool,
) -> (Option<SourceFile>, Vec<Diagnostic>) {
    // The parser reads the limit from its state: one grammar, built once per
    // thread, serves every item and file.
    let mut limit = SimpleState(limit);
    GRAMMAR.with(|g| {
        if quick {
            let quick = if item {
                g.quick_item.get().parse_with_state(token_stream(tokens, eoi), &mut limit)
            } else {
                g.quick_file.get().parse_with_state(token_stream(tokens, eoi), &mut limit)
            };
            if !quick.has_errors() {
                return (quick.into_output(), Vec::new());
            }
        }
        let stream = token_stream(tokens, eoi);
        let (file, errors) = if item {
            g.item.get().parse_with_state(stream, &mut limit)
        } else {
            g.file.get().parse_with_state(stream, &mut limit)
        }
        .into_output_errors();
        (file, errors.into_iter().map(rich_to_diagnostic).collect())
    })
}

/// The parser's input. One lifetime: [`In`] is invariant in the tokens'
/// lifetime, and the cached grammar is used with `In<'t, 't>`.
fn token_stream<'t>(tokens: &'t [(Token<'t>, SimpleSpan)], eoi: SimpleSpan) -> In<'t, 't> {
    tokens.map(eoi, |(t, s)| (t, s))
}

/// The grammar of a whole file (`ITEM = false`) or of one item followed by
/// the next one's keyword (`ITEM = true`), for any input lifetime: building
/// it allocates hundreds of boxed combinators, so each thread builds it once
/// ([`GRAMMAR`]) instead of once per item.
#[derive(Default)]
struct Grammar<const ITEM: bool>;

impl<const ITEM: bool> Cached for Grammar<ITEM> {
    type Parser<'t> = Boxed<'t, 't, In<'t, 't>, SourceFile, Ex<Rich<'t, Token<'t>, SimpleSpan>>>;

    fn make_parser<'t>(self) -> Self::Parser<'t> {
        item_parser(ITEM)
    }
}

/// The same grammar without error reporting. Most texts have no syntax
/// error: the quick pass gives their tree without building an error for
/// every alternative tried; a text with an error is parsed again with
/// [`Grammar`] (the tree is the same whenever no error was emitted: error
/// recovery only runs after an error).
#[derive(Default)]
struct QuickGrammar<const ITEM: bool>;

impl<const ITEM: bool> Cached for QuickGrammar<ITEM> {
    type Parser<'t> = Boxed<'t, 't, In<'t, 't>, SourceFile, Ex<EmptyErr>>;

    fn make_parser<'t>(self) -> Self::Parser<'t> {
        item_parser(ITEM)
    }
}

struct Grammars {
    file: Cache<Grammar<false>>,
    item: Cache<Grammar<true>>,
    quick_file: Cache<QuickGrammar<false>>,
    quick_item: Cache<QuickGrammar<true>>,
}

thread_local! {
    static GRAMMAR: Grammars = Grammars {
        file: Cache::default(),
        item: Cache::default(),
        quick_file: Cache::default(),
        quick_item: Cache::default(),
    };
}

/// Custom errors carry their code and help in the message, separated by `\u{1}`.
fn custom(code: &str, msg: impl std::fmt::Display, help: &str) -> String {
    format!("{code}\u{1}{msg}\u{1}{help}")
}

pub(super) fn name<'t, 's: 't, I, R>() -> impl Parser<'t, I, Name, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    select! { Token::Ident(s) = e => Name { text: s.to_string(), span: Span::from(e.span()) } }.labelled("identifier")
}

pub(super) fn number<'t, 's: 't, I, R>() -> impl Parser<'t, I, Number, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    select! { Token::Num(s) = e => Number { text: s.to_string(), span: Span::from(e.span()) } }.labelled("number")
}

/// A contextual word lexed as an identifier, e.g. `c`, `v`, `a`, `e`, `mutex`.
pub(super) fn word<'t, 's: 't, I, R>(
    w: &'static str,
    label: &'static str,
) -> impl Parser<'t, I, Span, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    select! { Token::Ident(s) = e if s == w => Span::from(e.span()) }.labelled(label)
}

pub(super) fn kw<'t, 's: 't, I, R>(k: Kw) -> impl Parser<'t, I, Span, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    just(Token::Kw(k)).map_with(|_, e| Span::from(e.span()))
}

/// Any balanced token tree: a delimited group or a single non-delimiter token.
pub(super) fn token_tree<'t, 's: 't, I, R>() -> impl Parser<'t, I, (), Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    recursive(|tt| {
        let group = |o: Token<'static>, c: Token<'static>| tt.clone().repeated().delimited_by(just(o), just(c));
        choice((
            group(Token::LBrace, Token::RBrace),
            group(Token::LParen, Token::RParen),
            group(Token::LBracket, Token::RBracket),
            none_of([Token::LBrace, Token::RBrace, Token::LParen, Token::RParen, Token::LBracket, Token::RBracket])
                .ignored(),
        ))
        .ignored()
    })
    .boxed()
}

/// `p` repeated inside a braced list of `;`-terminated definitions. A broken
/// definition is skipped up to and including its `;` (or up to the `}`).
pub(super) fn semi_list<'t, 's: 't, I, R, T>(
    p: impl Parser<'t, I, T, Ex<R>> + Clone + 't,
) -> Boxed<'t, 't, I, Vec<T>, Ex<R>>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
    T: 't,
{
    let skip = token_tree()
        .and_is(none_of([Token::Semi, Token::RBrace]).ignored())
        .repeated()
        .then(just(Token::Semi).or_not())
        .ignored();
    let item = p
        .then_ignore(just(Token::Semi))
        .map(Some)
        .recover_with(via_parser(none_of([Token::RBrace]).rewind().ignore_then(skip).map(|_| None)));
    none_of([Token::RBrace])
        .rewind()
        .ignore_then(item)
        .repeated()
        .collect::<Vec<Option<T>>>()
        .map(|v| v.into_iter().flatten().collect())
        .boxed()
}

/// `{ ... }` whose contents, if they fail to parse, become `fallback`.
pub(super) fn braced<'t, 's: 't, I, R, T: 't>(
    p: impl Parser<'t, I, T, Ex<R>> + Clone + 't,
    fallback: impl Fn() -> T + Clone + 't,
) -> Boxed<'t, 't, I, T, Ex<R>>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    p.delimited_by(just(Token::LBrace), just(Token::RBrace))
        .recover_with(via_parser(
            just(Token::LBrace)
                .ignore_then(token_tree().repeated())
                .then_ignore(just(Token::RBrace))
                .map(move |_| fallback()),
        ))
        .boxed()
}

pub(super) fn value<'t, 's: 't, I, R>() -> impl Parser<'t, I, Value, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    recursive(|value| {
        let list = value
            .separated_by(just(Token::Comma))
            .allow_trailing()
            .collect::<Vec<_>>()
            .delimited_by(just(Token::LBracket), just(Token::RBracket))
            .recover_with(via_parser(
                just(Token::LBracket)
                    .ignore_then(token_tree().repeated())
                    .then_ignore(just(Token::RBracket))
                    .to(Vec::new()),
            ));
        let string = select! { Token::Str(s) => ValueKind::Str(unescape(s)) }.labelled("string");
        choice((
            name().then(list.clone().or_not()).map(|(n, l)| match l {
                Some(items) => ValueKind::List { tag: Some(n), items },
                None => ValueKind::Ident(n),
            }),
            number().map(ValueKind::Number),
            string,
            list.map(|items| ValueKind::List { tag: None, items }),
        ))
        .map_with(|kind, e| Value { kind, span: Span::from(e.span()) })
        .labelled("value")
    })
    .boxed()
}

fn stmt_error(span: Span) -> Stmt {
    Stmt { kind: StmtKind::Error, span }
}

fn empty_block(span: Span) -> Block {
    Block { stmts: vec![stmt_error(span)], span }
}

/// Tokens that end a statement list used as a bare condition
/// (`if A then { B }`, `while A do { B }`); never consumed by statement recovery.
const STMT_STOP: [Token<'static>; 7] = [
    Token::LBrace,
    Token::RBrace,
    Token::RParen,
    Token::RBracket,
    Token::Kw(Kw::Then),
    Token::Kw(Kw::Do),
    Token::Kw(Kw::Else),
];

/// Tokens that end a statement list between delimiters (`{ ... }`, `( ... )`).
/// The token stream is balanced, so the first of them is the list's own
/// closing delimiter: a delimited list always extends to it, and a broken
/// statement is skipped up to the next `;` or that delimiter (skipping whole
/// `{ ... }` groups), never further and never less.
const CLOSERS: [Token<'static>; 3] = [Token::RBrace, Token::RParen, Token::RBracket];

fn block<'t, 's: 't, I, R>(
    stmt: impl Parser<'t, I, Stmt, Ex<R>> + Clone + 't,
    stops: &'static [Token<'static>],
) -> Boxed<'t, 't, I, Block, Ex<R>>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    // A statement that fails is skipped up to the next `;` or stop token.
    let skip = token_tree().and_is(none_of([Token::Semi]).ignored()).and_is(none_of(stops).ignored()).repeated();
    let recovering = stmt.recover_with(via_parser(
        token_tree().and_is(none_of(stops).ignored()).then(skip).map_with(|_, e| stmt_error(Span::from(e.span()))),
    ));
    let item = none_of(stops)
        .rewind()
        .ignore_then(recovering)
        .then(just(Token::Semi).map_with(|_, e| Span::from(e.span())).or_not());
    item.repeated().collect::<Vec<(Stmt, Option<Span>)>>().validate(|items, e, emitter| {
        let span = Span::from(e.span());
        if items.is_empty() {
            emitter.emit(R::custom(
                e.span(),
                custom(codes::EMPTY_BLOCK, "expected a statement", "a block holds at least one task call or control structure; use `Void()` for a task that does nothing"),
            ));
            return empty_block(span);
        }
        let n = items.len();
        let mut stmts = Vec::with_capacity(n);
        let next_ok: Vec<bool> = items.iter().skip(1).map(|(s, _)| s.kind != StmtKind::Error).collect();
        for (i, (s, semi)) in items.into_iter().enumerate() {
            // Only between two statements that parsed: after or before a
            // broken one, the error already reported is enough.
            if i + 1 < n && semi.is_none() && s.kind != StmtKind::Error && next_ok[i] {
                emitter.emit(R::custom(
                    SimpleSpan::from(s.span.end as usize..s.span.end as usize),
                    custom(codes::UNEXPECTED_TOKEN, "expected `;` between two statements", "`;` runs the statement before it, then the statement after it"),
                ));
            }
            stmts.push(s);
        }
        Block { stmts, span }
    })
    .boxed()
}

fn stmt<'t, 's: 't, I, R>() -> impl Parser<'t, I, Stmt, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    recursive(|stmt| {
        let bare_block = block(stmt.clone().boxed(), &STMT_STOP).boxed();
        let block = block(stmt.boxed(), &CLOSERS).boxed();
        let braced_block = braced(block.clone(), || empty_block(Span::default()))
            .map_with(|mut b: Block, e| {
                b.span = Span::from(e.span());
                b
            })
            .labelled("`{ ... }`")
            .boxed();
        let paren_block = block
            .clone()
            .delimited_by(just(Token::LParen), just(Token::RParen))
            .recover_with(via_parser(
                just(Token::LParen)
                    .ignore_then(token_tree().repeated())
                    .then_ignore(just(Token::RParen))
                    .map_with(|_, e| empty_block(Span::from(e.span()))),
            ))
            .boxed();
        // A condition: `( A )`, `{ A }` or a bare statement list ending at `then`/`do`.
        let cond = choice((paren_block.clone(), braced_block.clone(), bare_block)).boxed();

        let args = value()
            .separated_by(just(Token::Comma))
            .allow_trailing()
            .collect::<Vec<_>>()
            .delimited_by(just(Token::LParen), just(Token::RParen))
            .map_with(|args, e| (args, Span::from(e.span())))
            .recover_with(via_parser(
                just(Token::LParen)
                    .ignore_then(token_tree().repeated())
                    .then_ignore(just(Token::RParen))
                    .map_with(|_, e| (Vec::new(), Span::from(e.span()))),
            ));
        let call = name()
            .then(args)
            .then(just(Token::Colon).ignore_then(name()).or_not())
            .map_with(|((name, (args, args_span)), label), e| {
                StmtKind::Call(Call { name, args, args_span, label, span: Span::from(e.span()) })
            })
            .labelled("task call")
            .boxed();

        let while_ = kw(Kw::While)
            .then(cond.clone())
            .then_ignore(kw(Kw::Do).or_not())
            .then(braced_block.clone())
            .map(|((keyword, cond), body)| StmtKind::While { keyword, cond, body })
            .boxed();

        let else_ = kw(Kw::Else).then(braced_block.clone()).map(|(_, b)| (b, None));
        // Table B.4 writes the else branch as `then { C }`: accepted, linted.
        let then_as_else = kw(Kw::Then).then(braced_block.clone()).map(|(s, b)| (b, Some(s)));
        let if_ = kw(Kw::If)
            .then(cond.clone())
            .then_ignore(kw(Kw::Then).or_not())
            .then(braced_block.clone())
            .then(else_.or(then_as_else).or_not())
            .map(|(((keyword, cond), then), otherwise)| {
                let (otherwise, then_spelling) = match otherwise {
                    Some((b, s)) => (Some(b), s),
                    None => (None, None),
                };
                StmtKind::If { keyword, cond, then, otherwise, else_written_then: then_spelling }
            })
            .boxed();

        let par_op = kw(Kw::And).map(|s| (ParallelOp::And, s)).or(kw(Kw::Or).map(|s| (ParallelOp::Or, s)));
        let parallel = kw(Kw::Parallel)
            .then(braced_block.clone())
            .then(par_op.then(braced_block.clone()).repeated().at_least(1).collect::<Vec<_>>())
            .map(|((keyword, first), rest)| {
                let mut branches = vec![first];
                let mut ops = Vec::new();
                for (op, b) in rest {
                    ops.push(op);
                    branches.push(b);
                }
                StmtKind::Parallel { keyword, branches, ops }
            })
            .boxed();

        let try_ = kw(Kw::Try)
            .then(braced_block.clone())
            .then_ignore(kw(Kw::Catch))
            .then(braced_block.clone())
            .map(|((keyword, body), catch)| StmtKind::Try { keyword, body, catch })
            .boxed();

        let not = kw(Kw::Not)
            .then(paren_block.clone().or(braced_block.clone()))
            .map(|(keyword, body)| StmtKind::Not { keyword, body })
            .boxed();

        let handler_kind = kw(Kw::Condition)
            .map(|s| (MonitorKind::Condition, s))
            .or(kw(Kw::WhileCondition).map(|s| (MonitorKind::WhileCondition, s)));
        let handler = handler_kind.then(cond.clone()).then_ignore(kw(Kw::Do)).then(braced_block.clone()).map_with(
            |(((kind, keyword_span), condition), action), e| MonitorHandler {
                kind,
                keyword_span,
                condition,
                action,
                span: Span::from(e.span()),
            },
        );
        let monitor = kw(Kw::Monitor)
            .then(braced_block.clone())
            .then(handler.repeated().at_least(1).collect::<Vec<_>>())
            .map(|((keyword, body), handlers)| StmtKind::Monitor { keyword, body, handlers })
            .boxed();

        choice((call, while_, if_, parallel, try_, not, monitor))
            .map_with(|kind, e| Stmt { kind, span: Span::from(e.span()) })
            .labelled("statement")
    })
    .boxed()
}

/// The grammar of a file; with `Some(limit)`, of one item followed by the
/// keyword of the next one (at `limit`), which is not parsed.
fn item_parser<'t, 's: 't, R: Fail<'t, In<'t, 's>>>(one_item: bool) -> Boxed<'t, 't, In<'t, 's>, SourceFile, Ex<R>> {
    // import "path";
    let string = select! { Token::Str(s) = e => (unescape(s), Span::from(e.span())) }.labelled("string");
    // A missing `;` is one error after the path, and the import is kept (so
    // that the names it brings are still defined).
    let import = kw(Kw::Import).then(string).then(just(Token::Semi).or_not()).validate(
        |((_, (path, path_span)), semi), e, emitter| {
            if semi.is_none() {
                emitter.emit(R::custom(
                    SimpleSpan::from(path_span.end as usize..path_span.end as usize),
                    custom(
                        codes::UNEXPECTED_TOKEN,
                        "expected `;` after the imported file",
                        "write `import \"file.mcl\";`",
                    ),
                ));
            }
            Item::Import(Import { path, path_span, span: Span::from(e.span()) })
        },
    );

    // actions { name = Primitive( c: cmd, v: x, ... ); }
    enum ActionArg {
        Command(Name),
        Param(Value),
    }
    let action_arg = choice((
        word("c", "`c:`").ignore_then(just(Token::Colon)).ignore_then(name()).map(ActionArg::Command),
        word("v", "`v:`").ignore_then(just(Token::Colon)).ignore_then(value()).map(ActionArg::Param),
    ));
    let action_args = action_arg
        .separated_by(just(Token::Comma))
        .allow_trailing()
        .collect::<Vec<_>>()
        .validate(|args, e, emitter| {
            let mut command = None;
            let mut params = Vec::new();
            for a in args {
                match a {
                    ActionArg::Command(c) if command.is_none() => command = Some(c),
                    ActionArg::Command(c) => emitter.emit(R::custom(
                        SimpleSpan::from(c.span.range()),
                        custom(
                            codes::MISSING_COMMAND,
                            "an action has exactly one command `c: ...`",
                            "keep one `c:` and pass values with `v:`",
                        ),
                    )),
                    ActionArg::Param(v) => params.push(v),
                }
            }
            if command.is_none() {
                emitter.emit(R::custom(
                    e.span(),
                    custom(
                        codes::MISSING_COMMAND,
                        "an action needs a command `c: ...`",
                        "write the command first, e.g. `GotoPrimitive( c: enable, v: way-point )`",
                    ),
                ));
            }
            (command, params)
        })
        .delimited_by(just(Token::LParen), just(Token::RParen));
    let action = name()
        .then_ignore(just(Token::Eq))
        .then(name())
        .then(action_args)
        .map_with(|((name, primitive), (command, params)), e| ActionDef {
            name,
            primitive,
            command,
            params,
            span: Span::from(e.span()),
        })
        .boxed();
    let actions = kw(Kw::Actions)
        .ignore_then(braced(semi_list(action), Vec::new))
        .map_with(|actions, e| Item::Actions(ActionsBlock { actions, span: Span::from(e.span()) }));

    let events = kw(Kw::Events)
        .ignore_then(braced(semi_list(name()), Vec::new))
        .map_with(|events, e| Item::Events(EventsBlock { events, span: Span::from(e.span()) }));

    // Patterns.
    let iface = just(Token::Dot).ignore_then(number());
    let paren_num = number().delimited_by(just(Token::LParen), just(Token::RParen));
    let place =
        name().then(iface.clone().or_not()).then(paren_num.clone().or_not()).then(iface.clone().or_not()).map_with(
            |(((name, i1), tokens), i2), e| PlaceDef { name, interface: i1.or(i2), tokens, span: Span::from(e.span()) },
        );
    let delay = choice((number().map(Delay::Fixed), name().map(Delay::Param)))
        .delimited_by(just(Token::LParen), just(Token::RParen));
    let transition = name().then(iface.clone().or_not()).then(delay.or_not()).then(iface.clone().or_not()).map_with(
        |(((name, i1), delay), i2), e| TransitionDef { name, interface: i1.or(i2), delay, span: Span::from(e.span()) },
    );
    let node_ref = name().then(iface.clone().or_not()).map(|(name, interface)| NodeRef { name, interface });
    let arc = node_ref
        .clone()
        .then_ignore(just(Token::Arrow))
        .then(node_ref)
        .then(paren_num.or_not())
        .map_with(|((source, target), weight), e| ArcDef { source, target, weight, span: Span::from(e.span()) });
    let section = |k: Kw| kw(k).ignored();
    let net = section(Kw::Places)
        .ignore_then(braced(semi_list(place), Vec::new))
        .then(section(Kw::Transitions).ignore_then(braced(semi_list(transition), Vec::new)))
        .then(section(Kw::Arcs).ignore_then(braced(semi_list(arc), Vec::new)))
        .map(|((places, transitions), arcs)| PatternNet { places, transitions, arcs })
        .boxed();
    let file_name = choice((
        select! { Token::Str(s) => unescape(s) },
        name().then(just(Token::Dot).ignore_then(name()).repeated().collect::<Vec<_>>()).map(|(first, rest)| {
            let mut s = first.text;
            for n in rest {
                s.push('.');
                s.push_str(&n.text);
            }
            s
        }),
    ))
    .map_with(|path, e| (path, Span::from(e.span())))
    .labelled("file name");
    let pattern_body = choice((
        just(Token::Colon)
            .ignore_then(file_name)
            .then_ignore(just(Token::Semi))
            .map(|(path, path_span)| PatternBody::File { path, path_span }),
        braced(net.map(PatternBody::Net), || PatternBody::Net(PatternNet::default())),
    ));
    let pattern = name()
        .then(pattern_body)
        .map_with(|(name, body), e| Pattern { name, body, span: Span::from(e.span()) })
        .boxed();
    let pattern_item = none_of([Token::RBrace])
        .rewind()
        .ignore_then(
            pattern.map(Some).recover_with(via_parser(
                // A broken pattern keeps its name, so that its uses are not
                // reported as undefined (the checker skips its checks).
                name()
                    .or_not()
                    .rewind()
                    .then(
                        token_tree()
                            .and_is(none_of([Token::RBrace]).ignored())
                            .then(
                                token_tree()
                                    .and_is(none_of([Token::RBrace]).ignored())
                                    .and_is(none_of([Token::LBrace]).ignored())
                                    .repeated(),
                            )
                            .then(just(Token::Semi).or_not()),
                    )
                    .map_with(|(name, _), e| {
                        name.map(|name| Pattern {
                            name,
                            body: PatternBody::Net(PatternNet::default()),
                            span: Span::from(e.span()),
                        })
                    }),
            )),
        )
        .repeated()
        .collect::<Vec<Option<Pattern>>>()
        .map(|v| v.into_iter().flatten().collect::<Vec<_>>());
    let patterns = kw(Kw::Pattern)
        .or(kw(Kw::Patterns))
        .ignore_then(braced(pattern_item, Vec::new))
        .map_with(|patterns, e| Item::Patterns(PatternsBlock { patterns, span: Span::from(e.span()) }));

    // Tasks.
    let name_list = name().separated_by(just(Token::Comma)).allow_trailing().collect::<Vec<_>>();
    let binding_kind = word("a", "`a:`").to(BindingKind::Action).or(word("e", "`e:`").to(BindingKind::Event));
    let binding = binding_kind
        .then_ignore(just(Token::Colon))
        .then(name())
        .then_ignore(just(Token::Arrow))
        .then(name().separated_by(just(Token::Comma)).at_least(1).collect::<Vec<_>>())
        .map_with(|((kind, target), transitions), e| Binding { kind, target, transitions, span: Span::from(e.span()) });
    let task = name()
        .then(name_list.clone().delimited_by(just(Token::LParen), just(Token::RParen)))
        .then(just(Token::Colon).ignore_then(name()).or_not())
        .then(braced(semi_list(binding), Vec::new))
        .map_with(|(((name, params), pattern), bindings), e| TaskDef {
            name,
            params,
            pattern,
            bindings,
            span: Span::from(e.span()),
        })
        .boxed();
    let task_item = none_of([Token::RBrace])
        .rewind()
        .ignore_then(
            task.map(Some).recover_with(via_parser(
                // A broken task keeps its name, so that its calls are not
                // reported as undefined (the checker skips its checks).
                name()
                    .or_not()
                    .rewind()
                    .then(
                        token_tree()
                            .and_is(none_of([Token::RBrace]).ignored())
                            .then(token_tree().and_is(none_of([Token::RBrace, Token::LBrace]).ignored()).repeated())
                            .then(token_tree().and_is(just(Token::LBrace).ignored()).or_not()),
                    )
                    .map_with(|(name, _), e| {
                        name.map(|name| TaskDef {
                            name,
                            params: Vec::new(),
                            pattern: None,
                            bindings: Vec::new(),
                            span: Span::from(e.span()),
                        })
                    }),
            )),
        )
        .repeated()
        .collect::<Vec<Option<TaskDef>>>()
        .map(|v| v.into_iter().flatten().collect::<Vec<_>>());
    let tasks = kw(Kw::Tasks)
        .ignore_then(braced(task_item, Vec::new))
        .map_with(|tasks, e| Item::Tasks(TasksBlock { tasks, span: Span::from(e.span()) }));

    // Missions.
    let body = braced(block(stmt().boxed(), &CLOSERS), || empty_block(Span::default())).map_with(|mut b: Block, e| {
        if b.span == Span::default() {
            b.span = Span::from(e.span());
        }
        b
    });
    let params = name_list
        .delimited_by(just(Token::LParen), just(Token::RParen))
        .recover_with(via_parser(
            just(Token::LParen).ignore_then(token_tree().repeated()).then_ignore(just(Token::RParen)).to(Vec::new()),
        ))
        .map_with(|p, e| (p, Span::from(e.span())));
    let placement = name()
        .then_ignore(word("at", "`at`"))
        .then(number())
        .delimited_by(just(Token::LBracket), just(Token::RBracket))
        .map_with(|p, e| (p, Span::from(e.span())));
    let starts_item = any().filter(|t: &Token<'_>| matches!(t, Token::Kw(k) if k.starts_item()));
    // Anything else before the body's `{` is reported once and skipped, so
    // that the body is still parsed.
    let junk = any()
        .filter(|t: &Token<'_>| *t != Token::LBrace && !matches!(t, Token::Kw(k) if k.starts_item()))
        .map_with(|t, e| (t, e.span()))
        .rewind()
        .then_ignore(
            token_tree().and_is(none_of([Token::LBrace]).ignored()).and_is(starts_item.not()).repeated().at_least(1),
        )
        .validate(|(t, span), _, emitter| {
            emitter.emit(R::custom(span, custom(codes::UNEXPECTED_TOKEN, format!("expected `{{`, found {t}"), "")));
        });
    // Every part of the header is parsed as optional, and the combination
    // is checked afterwards: a malformed header is one error, and the
    // mission is kept.
    // `mission : while { ... }`: a keyword where the name goes is one error,
    // and the mission keeps it as its name.
    let kw_name =
        any().filter(|t: &Token<'_>| matches!(t, Token::Kw(k) if !k.starts_item())).validate(|t, e, emitter| {
            let text = match t {
                Token::Kw(k) => k.as_str(),
                _ => "",
            };
            emitter.emit(R::custom(
                e.span(),
                custom(
                    codes::UNEXPECTED_TOKEN,
                    format!("`{text}` is a keyword and cannot be a mission's name"),
                    "choose another name",
                ),
            ));
            Name { text: text.to_string(), span: Span::from(e.span()) }
        });
    let header = just(Token::Colon)
        .map_with(|_, e| Span::from(e.span()))
        .or_not()
        .then(name().or(kw_name).or_not())
        .then(params.or_not())
        .then(placement.or_not())
        .then_ignore(junk.or_not())
        .boxed();
    let mission = kw(Kw::Mission)
        .to(MissionKind::Mission)
        .or(kw(Kw::PlanOp).to(MissionKind::PlanOp))
        .map_with(|k, e| (k, Span::from(e.span())))
        .then(header)
        .then(body.clone())
        .validate(|(((kind, keyword_span), (((colon, name), params), placement)), body), e, emitter| {
            let mut error = |span: Span, msg: &str, help: &str| {
                emitter.emit(R::custom(SimpleSpan::from(span.range()), custom(codes::UNEXPECTED_TOKEN, msg, help)));
            };
            let name_span = name.as_ref().map(|n: &Name| n.span);
            match kind {
                MissionKind::Mission => {
                    if let (Some(c), None) = (colon, &name) {
                        error(c, "expected the mission's name after `:`", "write `mission : name { ... }`");
                    }
                    if let (Some(_), Some((_, ps))) = (colon, &params) {
                        error(*ps, "a named mission has no parameters", "a parametrised mission is written without `:`: `mission Name( x, y ) { ... }`");
                    }
                    if let (None, Some(ns), None) = (colon, name_span, &params) {
                        error(ns, "expected `:` before the mission's name", "write `mission : name { ... }`, or `mission Name( ... ) { ... }` for a parametrised mission");
                    }
                    if let (None, None, Some((_, ps))) = (colon, name_span, &params) {
                        error(*ps, "a parametrised mission needs a name", "write `mission Name( x, y ) { ... }`");
                    }
                    if let (Some((_, ps)), true) = (&placement, colon.is_none() || params.is_some()) {
                        error(*ps, "`[ ID at NUM ]` follows the name of a named mission", "write `mission : name [ ID at NUM ] { ... }`");
                    }
                }
                MissionKind::PlanOp => {
                    if let Some(c) = colon {
                        error(c, "`mcl_plan_op` is followed by the operator's name, without `:`", "write `mcl_plan_op Name( x, y ) { ... }`");
                    }
                    match (name_span, &params) {
                        (None, _) => error(Span::at(keyword_span.end as usize), "expected the operator's name after `mcl_plan_op`", "write `mcl_plan_op Name( x, y ) { ... }`"),
                        (Some(ns), None) => error(Span::at(ns.end as usize), "expected the operator's parameters `( ... )`", "an operator without parameters is written `mcl_plan_op Name() { ... }`"),
                        _ => {}
                    }
                    if let Some((_, ps)) = &placement {
                        error(*ps, "an operator has no `[ ID at NUM ]` part", "remove it");
                    }
                }
            }
            let (params, _) = params.unwrap_or_default();
            let placement = placement.map(|(p, _)| p);
            Item::Mission(Mission { kind, keyword_span, name, params, placement, body, span: Span::from(e.span()) })
        });

    // Constraints.
    let label_ref = name().then(just(Token::Colon).ignore_then(name()).or_not()).map_with(|(a, b), e| match b {
        Some(label) => LabelRef { mission: Some(a), label, span: Span::from(e.span()) },
        None => LabelRef { mission: None, label: a, span: Span::from(e.span()) },
    });
    let refs = label_ref.separated_by(just(Token::Comma)).allow_trailing().collect::<Vec<_>>();
    let constraint_kw = choice((
        word("mutex", "`mutex`").map(|s| (ConstraintKind::Mutex, s, false)),
        word("_mutex_", "`_mutex_`").map(|s| (ConstraintKind::Mutex, s, true)),
        word("order", "`order`").map(|s| (ConstraintKind::Order, s, false)),
        word("_order_", "`_order_`").map(|s| (ConstraintKind::Order, s, true)),
        word("sync", "`sync`").map(|s| (ConstraintKind::Sync, s, false)),
        word("_sync_", "`_sync_`").map(|s| (ConstraintKind::Sync, s, true)),
    ))
    .labelled("`mutex`, `order` or `sync`");
    let constraint = constraint_kw
        .clone()
        .then(braced(refs, Vec::new))
        .then(just(Token::Eq).ignore_then(number()).or_not())
        .then_ignore(just(Token::Semi).or_not())
        .map_with(|(((kind, keyword_span, bnf_spelling), refs), bound), e| Constraint {
            kind,
            keyword_span,
            bnf_spelling,
            refs,
            bound,
            span: Span::from(e.span()),
        });
    let constraint_item = none_of([Token::RBrace])
        .rewind()
        .ignore_then(
            constraint.map(Some).recover_with(via_parser(
                // Skip to the next constraint keyword, `;` (included) or `}`.
                token_tree()
                    .and_is(none_of([Token::RBrace]).ignored())
                    .then(
                        token_tree()
                            .and_is(none_of([Token::RBrace, Token::Semi]).ignored())
                            .and_is(constraint_kw.clone().not())
                            .repeated(),
                    )
                    .then(just(Token::Semi).or_not())
                    .to(None),
            )),
        )
        .repeated()
        .collect::<Vec<Option<Constraint>>>()
        .map(|v| v.into_iter().flatten().collect::<Vec<_>>());
    let constraints = kw(Kw::Constraints)
        .ignore_then(braced(constraint_item, Vec::new))
        .map_with(|constraints, e| Item::Constraints(ConstraintsBlock { constraints, span: Span::from(e.span()) }));

    let item = choice((
        import.boxed(),
        actions.boxed(),
        events.boxed(),
        patterns.boxed(),
        tasks.boxed(),
        mission.boxed(),
        constraints.boxed(),
        planning_item().boxed(),
        pddl_map_item().boxed(),
    ))
    .labelled("item");
    let skip_item = token_tree()
        .then(token_tree().and_is(starts_item.not()).repeated())
        .map_with(|_, e| {
            let _ = e.span();
        })
        .to(None);
    let before_limit = any()
        .try_map_with(|_, e| {
            let span: SimpleSpan = e.span();
            let limit: &mut SimpleState<usize> = e.state();
            if span.start >= **limit {
                Err(R::custom(span, String::new()))
            } else {
                Ok(())
            }
        })
        .rewind();
    let items = before_limit
        .ignore_then(item.map(Some).recover_with(via_parser(skip_item)))
        .repeated()
        .collect::<Vec<Option<Item>>>()
        .map(|v| SourceFile { items: v.into_iter().flatten().collect() });
    if one_item {
        items.then_ignore(any()).then_ignore(end()).boxed()
    } else {
        items.then_ignore(end()).boxed()
    }
}
