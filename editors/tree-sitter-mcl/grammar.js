/**
 * @file Tree-sitter grammar of MCL, the Mission Control Language of
 *       autonomous underwater vehicles (docs/language.md in the MCL repository).
 * @license MIT OR Apache-2.0
 *
 * The grammar accepts every spelling that the reference parser
 * (mcl-syntax/src/parser.rs) accepts: `->` and `→`, `pattern` and `patterns`,
 * `mutex`/`order`/`sync` and `_mutex_`/`_order_`/`_sync_`, conditions written
 * `( A )`, `{ A }` or bare, the optional `then`/`do`, `then` for `else`
 * (Table B.4), `mission : name [ ID at NUM ]`, `mission Name( ... )` and
 * `mcl_plan_op Name( ... )`, PNML patterns `P_X : file.xml;`.
 *
 * Known difference: an identifier ending with `-` or `/` (`a-`, allowed by
 * the MCL lexer) is not an identifier here; every other identifier is.
 */

/// <reference types="tree-sitter-cli/dsl" />
// @ts-check

/** `rule ( , rule )* ,?` */
function commaSep1(rule) {
  return seq(rule, repeat(seq(',', rule)), optional(','));
}

/** `( rule ( , rule )* ,? )?` */
function commaSep(rule) {
  return optional(commaSep1(rule));
}

module.exports = grammar({
  name: 'mcl',

  extras: $ => [/\s/, $.comment],

  word: $ => $.identifier,

  // The reserved words of MCL are never identifiers. The contextual words
  // (`c`, `v`, `a`, `e`, `at`, `mutex`, `_mutex_`, `order`, `_order_`,
  // `sync`, `_sync_`) are keywords only where the grammar expects them.
  reserved: {
    global: _ => [
      'import', 'actions', 'events', 'pattern', 'patterns', 'tasks', 'mission', 'mcl_plan_op', 'constraints',
      'places', 'transitions', 'arcs', 'while', 'if', 'then', 'else', 'do', 'parallel', 'and', 'or', 'try',
      'catch', 'not', 'monitor', 'condition', 'while_condition', 'planning', 'pddl_map',
    ],
  },

  conflicts: $ => [],

  rules: {
    source_file: $ => repeat($._item),

    _item: $ => choice(
      $.import,
      $.actions_block,
      $.events_block,
      $.patterns_block,
      $.tasks_block,
      $.mission,
      $.constraints_block,
      $.planning_block,
      $.pddl_map_block,
    ),

    // import "vehicle.mcl";
    import: $ => seq('import', field('path', $.string), ';'),

    // actions { name = Primitive( c: command, v: value, ... ); }
    actions_block: $ => seq('actions', '{', repeat($.action), '}'),
    action: $ => seq(
      field('name', $.identifier),
      '=',
      field('primitive', $.identifier),
      '(',
      // Exactly one `c: command`, anywhere among the `v:` parameters.
      repeat(seq($.parameter, ',')),
      $.command,
      repeat(seq(',', $.parameter)),
      optional(','),
      ')',
      ';',
    ),
    command: $ => seq('c', ':', field('name', $.identifier)),
    parameter: $ => seq('v', ':', field('value', $._value)),

    // events { e1; e2; }
    events_block: $ => seq('events', '{', repeat($.event), '}'),
    event: $ => seq(field('name', $.identifier), ';'),

    // pattern { Name { places {...} transitions {...} arcs {...} }  P_X : file.xml; }
    patterns_block: $ => seq(choice('pattern', 'patterns'), '{', repeat(choice($.pattern, $.pattern_file)), '}'),
    pattern: $ => seq(
      field('name', $.identifier),
      '{',
      $.places,
      $.transitions,
      $.arcs,
      '}',
    ),
    pattern_file: $ => seq(
      field('name', $.identifier),
      ':',
      field('path', choice($.string, $.file_name)),
      ';',
    ),
    file_name: $ => seq($.identifier, repeat(seq('.', $.identifier))),

    places: $ => seq('places', '{', repeat($.place), '}'),
    place: $ => seq(
      field('name', $.identifier),
      optional($.interface),
      optional(seq('(', field('tokens', $.number), ')')),
      optional($.interface),
      ';',
    ),
    transitions: $ => seq('transitions', '{', repeat($.transition), '}'),
    transition: $ => seq(
      field('name', $.identifier),
      optional($.interface),
      optional(seq('(', field('delay', choice($.number, $.identifier)), ')')),
      optional($.interface),
      ';',
    ),
    arcs: $ => seq('arcs', '{', repeat($.arc), '}'),
    arc: $ => seq(
      field('source', $.node_ref),
      $._arrow,
      field('target', $.node_ref),
      optional(seq('(', field('weight', $.number), ')')),
      ';',
    ),
    node_ref: $ => seq(field('name', $.identifier), optional($.interface)),
    interface: $ => seq('.', $.number),

    // tasks { Goto( way-point ): AchieveOneGoal { a: enableGoto -> T0; } }
    tasks_block: $ => seq('tasks', '{', repeat($.task), '}'),
    task: $ => seq(
      field('name', $.identifier),
      field('parameters', $.parameters),
      optional(seq(':', field('pattern', $.identifier))),
      '{',
      repeat($.binding),
      '}',
    ),
    binding: $ => seq(
      field('kind', choice('a', 'e')),
      ':',
      field('target', $.identifier),
      $._arrow,
      field('transition', $.identifier),
      repeat(seq(',', field('transition', $.identifier))),
      ';',
    ),
    parameters: $ => seq('(', commaSep($.identifier), ')'),

    // mission { ... }, mission : auv [ ID at NUM ] { ... },
    // mission Name( x ) { ... }, mcl_plan_op Name( x ) { ... }
    mission: $ => choice(
      seq(
        'mission',
        optional(seq(':', field('name', $.identifier), optional($.placement))),
        field('body', $.block),
      ),
      seq(
        choice('mission', 'mcl_plan_op'),
        field('name', $.identifier),
        field('parameters', $.parameters),
        field('body', $.block),
      ),
    ),
    placement: $ => seq('[', field('id', $.identifier), 'at', field('number', $.number), ']'),

    // Statements: `;` sequences them; a `;` before `}` is tolerated.
    block: $ => seq('{', $._statements, '}'),
    _statements: $ => seq($._statement, repeat(seq(';', $._statement)), optional(';')),
    _statement: $ => choice(
      $.call,
      $.not_statement,
      $.if_statement,
      $.while_statement,
      $.try_statement,
      $.parallel_statement,
      $.monitor_statement,
    ),

    // `( A )`, `{ A }`, or bare `A` before `then` / `do` / `{`.
    condition: $ => choice(
      seq('(', $._statements, ')'),
      seq('{', $._statements, '}'),
      $._statements,
    ),

    call: $ => seq(
      field('name', $.identifier),
      field('arguments', $.arguments),
      optional(seq(':', field('label', $.identifier))),
    ),
    arguments: $ => seq('(', commaSep($._value), ')'),

    not_statement: $ => seq(
      'not',
      field('body', alias(choice(seq('(', $._statements, ')'), seq('{', $._statements, '}')), $.condition)),
    ),
    if_statement: $ => prec.right(seq(
      'if',
      field('condition', $.condition),
      optional('then'),
      field('consequence', $.block),
      optional(seq(choice('else', 'then'), field('alternative', $.block))),
    )),
    while_statement: $ => seq(
      'while',
      field('condition', $.condition),
      optional('do'),
      field('body', $.block),
    ),
    try_statement: $ => seq('try', field('body', $.block), 'catch', field('handler', $.block)),
    parallel_statement: $ => prec.right(seq(
      'parallel',
      field('branch', $.block),
      repeat1(seq(choice('and', 'or'), field('branch', $.block))),
    )),
    monitor_statement: $ => prec.right(seq(
      'monitor',
      field('body', $.block),
      repeat1($.monitor_handler),
    )),
    monitor_handler: $ => seq(
      choice('condition', 'while_condition'),
      field('condition', $.condition),
      'do',
      field('action', $.block),
    ),

    // constraints { mutex { m:a, b } = 1  order { m:a, n:b }  sync { a, b } }
    constraints_block: $ => seq('constraints', '{', repeat($.constraint), '}'),
    constraint: $ => seq(
      field('kind', choice('mutex', '_mutex_', 'order', '_order_', 'sync', '_sync_')),
      '{',
      commaSep($.label_ref),
      '}',
      optional(seq('=', field('bound', $.number))),
      optional(';'),
    ),
    label_ref: $ => seq(
      optional(seq(field('mission', $.identifier), ':')),
      field('label', $.identifier),
    ),

    // planning { type ...; entity ...; function ...; operator ... { ... } initial { ... } goal { ... } }
    // (docs/language.md, section 13). Its words are contextual.
    planning_block: $ => seq('planning', '{', repeat($._plan_def), '}'),
    _plan_def: $ => choice($.plan_type, $.plan_entity, $.plan_function, $.plan_operator, $.plan_initial, $.plan_goal),
    plan_type: $ => seq(
      'type',
      field('name', $.identifier),
      optional(seq(':', field('parent', $.identifier))),
      choice(seq('{', repeat(seq(field('attribute', $.identifier), ';')), '}', optional(';')), ';'),
    ),
    plan_entity: $ => seq(
      'entity',
      field('type', $.identifier),
      field('name', $.identifier),
      choice(seq('{', repeat($.attribute_value), '}', optional(';')), ';'),
    ),
    attribute_value: $ => seq(field('name', $.identifier), '=', field('value', $._value), ';'),
    plan_function: $ => seq('function', field('name', $.identifier), field('parameters', $.parameters), ';'),
    plan_operator: $ => seq(
      'operator',
      field('name', $.identifier),
      '(',
      commaSep($.typed_parameter),
      ')',
      '{',
      repeat($._op_part),
      '}',
      optional(';'),
    ),
    typed_parameter: $ => seq(field('type', $.identifier), field('name', $.identifier)),
    _op_part: $ => choice($.fact_list, $.expression_list, $.cost, $.mcl_line),
    fact_list: $ => seq(
      field('kind', choice('precond', 'add', 'del')),
      '{',
      repeat(seq($.fact, ';')),
      '}',
      optional(';'),
    ),
    fact: $ => seq(
      optional('not'),
      field('subject', $.identifier),
      field('relation', $.identifier),
      optional(field('object', $.identifier)),
    ),
    expression_list: $ => seq('expression', '{', repeat(seq($.expression, ';')), '}', optional(';')),
    expression: $ => seq(
      field('left', $._operand),
      field('operator', choice('!=', '==', '=', '<', '<=', '>', '>=')),
      field('right', $._operand),
    ),
    cost: $ => seq('cost', field('value', $._operand), ';'),
    mcl_line: $ => seq('mcl', field('call', $.mission_call), ';'),
    mission_call: $ => seq(field('name', $.identifier), '(', commaSep($._operand), ')'),
    _operand: $ => choice($.attribute, $.function_value, $.identifier, $.number, $.string),
    attribute: $ => seq(field('entity', $.identifier), '.', field('name', $.identifier)),
    function_value: $ => seq(field('name', $.identifier), field('arguments', $.parameters)),
    plan_initial: $ => seq(
      'initial',
      '{',
      repeat(seq(choice($.fact, $.function_assignment), ';')),
      '}',
      optional(';'),
    ),
    function_assignment: $ => seq(
      field('name', $.identifier),
      field('arguments', $.parameters),
      '=',
      field('value', $._value),
    ),
    plan_goal: $ => seq('goal', '{', repeat(seq($.fact, ';')), '}', optional(';')),

    // pddl_map { move( v, l1, l2 ) -> MclMove( l2.x, l2.y, l2.z ); }
    pddl_map_block: $ => seq('pddl_map', '{', repeat($.mapping), '}'),
    mapping: $ => seq(
      field('action', $.identifier),
      field('parameters', $.parameters),
      $._arrow,
      field('call', $.mission_call),
      ';',
    ),

    // Values: call arguments and action parameters.
    _value: $ => choice($.identifier, $.number, $.string, $.list),
    list: $ => seq(optional(field('tag', $.identifier)), '[', commaSep($._value), ']'),

    _arrow: $ => choice('->', '→'),

    // Tokens. An identifier continues with letters, digits, `_`, `$`, `-`
    // and `/`, but `->` and `//`, `/*` end it.
    identifier: _ => /[A-Za-z_$][A-Za-z0-9_$]*((-|\/-)+\/?[A-Za-z0-9_$]+|\/[A-Za-z0-9_$]+)*/,
    number: _ => /-?(0|[1-9][0-9]*)(\.[0-9]+)?/,
    string: _ => /"([^"\\\n]|\\[^\n])*"/,
    comment: _ => token(choice(
      seq('//', /[^\n]*/),
      seq('/*', /[^*]*\*+([^/*][^*]*\*+)*/, '/'),
    )),
  },
});
