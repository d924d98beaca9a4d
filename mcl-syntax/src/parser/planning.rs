//! The grammar of the planning blocks: `planning { ... }` and
//! `pddl_map { ... }` (docs/planning.md). Every word inside these blocks is
//! contextual (lexed as an identifier), so that `type`, `goal` or `cost` stay
//! usable as names elsewhere.

use super::grammar::{braced, kw, name, number, semi_list, token_tree, value, word, Ex, Fail};
use crate::ast::*;
use crate::lexer::{unescape, Kw, Token};
use crate::span::Span;
use chumsky::input::ValueInput;
use chumsky::prelude::*;

/// Skips a broken definition of a planning block: up to and including its
/// `;`, or its `{ ... }` group, never past the block's `}`.
fn plan_skip<'t, 's: 't, I, R>() -> impl Parser<'t, I, (), Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    token_tree()
        .and_is(none_of([Token::RBrace]).ignored())
        .then(token_tree().and_is(none_of([Token::RBrace, Token::LBrace, Token::Semi]).ignored()).repeated())
        .then(just(Token::Semi).ignored().or(token_tree().and_is(just(Token::LBrace).ignored())).or_not())
        .ignored()
        .boxed()
}

/// `p` repeated until the enclosing `}`, each failure skipped with [`plan_skip`].
fn plan_list<'t, 's: 't, I, R, T: 't>(p: impl Parser<'t, I, T, Ex<R>> + Clone + 't) -> Boxed<'t, 't, I, Vec<T>, Ex<R>>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    none_of([Token::RBrace])
        .rewind()
        .ignore_then(p.map(Some).recover_with(via_parser(plan_skip().map(|_| None))))
        .repeated()
        .collect::<Vec<Option<T>>>()
        .map(|v| v.into_iter().flatten().collect())
        .boxed()
}

/// `( a, b, ... )`, possibly empty.
fn plan_names<'t, 's: 't, I, R>() -> impl Parser<'t, I, Vec<Name>, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    name()
        .separated_by(just(Token::Comma))
        .allow_trailing()
        .collect::<Vec<_>>()
        .delimited_by(just(Token::LParen), just(Token::RParen))
        .boxed()
}

/// An operand: `l2.x`, `distance( a, b )`, `l1`, a number or a string.
fn plan_operand<'t, 's: 't, I, R>() -> impl Parser<'t, I, PlanOperand, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    let string = select! { Token::Str(s) => ValueKind::Str(unescape(s)) }.labelled("string");
    let literal =
        number().map(ValueKind::Number).or(string).map_with(|kind, e| Value { kind, span: Span::from(e.span()) });
    choice((
        name().then_ignore(just(Token::Dot)).then(name()).map(|(n, a)| OperandKind::Attr(n, a)),
        name().then(plan_names()).map(|(n, args)| OperandKind::Function(n, args)),
        name().map(OperandKind::Name),
        literal.map(OperandKind::Literal),
    ))
    .map_with(|kind, e| PlanOperand { kind, span: Span::from(e.span()) })
    .labelled("operand")
    .boxed()
}

/// `Mission( arg, ... )`.
fn plan_call<'t, 's: 't, I, R>() -> impl Parser<'t, I, PlanCall, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    name()
        .then(
            plan_operand()
                .separated_by(just(Token::Comma))
                .allow_trailing()
                .collect::<Vec<_>>()
                .delimited_by(just(Token::LParen), just(Token::RParen)),
        )
        .map_with(|(name, args), e| PlanCall { name, args, span: Span::from(e.span()) })
        .labelled("mission call")
        .boxed()
}

/// A fact `[not] subject relation [object]`.
fn plan_fact<'t, 's: 't, I, R>() -> impl Parser<'t, I, PlanFact, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    kw(Kw::Not)
        .or_not()
        .then(name())
        .then(name())
        .then(name().or_not())
        .map_with(|(((negated, subject), relation), object), e| PlanFact {
            negated,
            subject,
            relation,
            object,
            span: Span::from(e.span()),
        })
        .labelled("fact `entity relation [entity]`")
        .boxed()
}

/// `{ fact; ... }`
fn plan_facts<'t, 's: 't, I, R>() -> impl Parser<'t, I, Vec<PlanFact>, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    braced(semi_list(plan_fact()), Vec::new).boxed()
}

/// `planning { ... }`
pub(super) fn planning_item<'t, 's: 't, I, R>() -> impl Parser<'t, I, Item, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    let end = just(Token::Semi).or_not().ignored();
    // type location { x; y; z; }  |  type robot;  |  type auv : robot;
    let attrs = braced(semi_list(name()), Vec::new).then_ignore(end).or(just(Token::Semi).to(Vec::new()));
    let ty =
        word("type", "`type`").then(name()).then(just(Token::Colon).ignore_then(name()).or_not()).then(attrs).map_with(
            |(((keyword_span, name), parent), attrs), e| {
                PlanDef::Type(PlanType { keyword_span, name, parent, attrs, span: Span::from(e.span()) })
            },
        );
    // entity location dock { x = 0; }  |  entity robot auv;
    let attr_value = name().then_ignore(just(Token::Eq)).then(value()).map_with(|(name, value), e| AttrValue {
        name,
        value,
        span: Span::from(e.span()),
    });
    let values = braced(semi_list(attr_value), Vec::new).then_ignore(end).or(just(Token::Semi).to(Vec::new()));
    let entity = word("entity", "`entity`").then(name()).then(name()).then(values).map_with(
        |(((keyword_span, ty), name), values), e| {
            PlanDef::Entity(PlanEntity { keyword_span, ty, name, values, span: Span::from(e.span()) })
        },
    );
    // function distance( zone, zone );
    let function =
        word("function", "`function`").then(name()).then(plan_names()).then_ignore(just(Token::Semi)).map_with(
            |((keyword_span, name), params), e| {
                PlanDef::Function(PlanFunction { keyword_span, name, params, span: Span::from(e.span()) })
            },
        );
    // operator move( vehicle v, location l1 ) { precond { ... } ... }
    let typed = name().then(name()).map(|(ty, name)| TypedParam { ty, name });
    let typed_params = typed
        .separated_by(just(Token::Comma))
        .allow_trailing()
        .collect::<Vec<_>>()
        .delimited_by(just(Token::LParen), just(Token::RParen));
    let expr = plan_operand()
        .then(
            select! { Token::Cmp(s) => s.to_string(), Token::Eq => "=".to_string() }
                .map_with(|op, e| (op, Span::from(e.span())))
                .labelled("comparison"),
        )
        .then(plan_operand())
        .map_with(|((left, (op, op_span)), right), e| PlanExpr { left, op, op_span, right, span: Span::from(e.span()) })
        .labelled("expression");
    let part_kind = choice((
        word("precond", "`precond`").then(plan_facts()).map(|(k, f)| (k, OpPartKind::Precond(f))),
        word("add", "`add`").then(plan_facts()).map(|(k, f)| (k, OpPartKind::Add(f))),
        word("del", "`del`").then(plan_facts()).map(|(k, f)| (k, OpPartKind::Del(f))),
        word("expression", "`expression`")
            .then(braced(semi_list(expr), Vec::new))
            .map(|(k, x)| (k, OpPartKind::Expression(x))),
        word("cost", "`cost`")
            .then(plan_operand())
            .then_ignore(just(Token::Semi))
            .map(|(k, c)| (k, OpPartKind::Cost(c))),
        word("mcl", "`mcl`").then(plan_call()).then_ignore(just(Token::Semi)).map(|(k, c)| (k, OpPartKind::Mcl(c))),
    ))
    .then_ignore(end)
    .map_with(|(keyword_span, kind), e| OpPart { keyword_span, kind, span: Span::from(e.span()) });
    let operator = word("operator", "`operator`")
        .then(name())
        .then(typed_params)
        .then(braced(plan_list(part_kind), Vec::new))
        .then_ignore(end)
        .map_with(|(((keyword_span, name), params), parts), e| {
            PlanDef::Operator(PlanOperator { keyword_span, name, params, parts, span: Span::from(e.span()) })
        });
    // initial { auv in deploy; distance( deploy, recovery ) = 5; }  |  goal { ... }
    enum Entry {
        Fact(PlanFact),
        Value(FunctionValue),
    }
    let fvalue =
        name().then(plan_names()).then_ignore(just(Token::Eq)).then(value()).map_with(|((name, args), value), e| {
            Entry::Value(FunctionValue { name, args, value, span: Span::from(e.span()) })
        });
    let entry = fvalue.or(plan_fact().map(Entry::Fact));
    let initial = word("initial", "`initial`").then(braced(semi_list(entry), Vec::new)).then_ignore(end).map_with(
        |(keyword_span, entries), e| {
            let mut facts = Vec::new();
            let mut values = Vec::new();
            for x in entries {
                match x {
                    Entry::Fact(f) => facts.push(f),
                    Entry::Value(v) => values.push(v),
                }
            }
            PlanDef::Facts(PlanFacts { keyword_span, goal: false, facts, values, span: Span::from(e.span()) })
        },
    );
    let goal = word("goal", "`goal`").then(plan_facts()).then_ignore(end).map_with(|(keyword_span, facts), e| {
        PlanDef::Facts(PlanFacts { keyword_span, goal: true, facts, values: Vec::new(), span: Span::from(e.span()) })
    });
    let def = choice((ty.boxed(), entity.boxed(), function.boxed(), operator.boxed(), initial.boxed(), goal.boxed()))
        .labelled("`type`, `entity`, `function`, `operator`, `initial` or `goal`");
    kw(Kw::Planning)
        .then(braced(plan_list(def), Vec::new))
        .map_with(|(keyword_span, defs), e| {
            Item::Planning(PlanningBlock { keyword_span, defs, span: Span::from(e.span()) })
        })
        .boxed()
}

/// `pddl_map { action( a, b ) -> Mission( b.x, 3 ); }`
pub(super) fn pddl_map_item<'t, 's: 't, I, R>() -> impl Parser<'t, I, Item, Ex<R>> + Clone + use<'t, 's, I, R>
where
    I: ValueInput<'t, Token = Token<'s>, Span = SimpleSpan>,
    R: Fail<'t, I>,
{
    let mapping = name()
        .then(plan_names())
        .then_ignore(just(Token::Arrow))
        .then(plan_call())
        .then_ignore(just(Token::Semi))
        .map_with(|((action, params), call), e| PddlMapping { action, params, call, span: Span::from(e.span()) })
        .labelled("mapping `action( params ) -> Mission( args );`");
    kw(Kw::PddlMap)
        .then(braced(plan_list(mapping), Vec::new))
        .map_with(|(keyword_span, maps), e| {
            Item::PddlMap(PddlMapBlock { keyword_span, maps, span: Span::from(e.span()) })
        })
        .boxed()
}
