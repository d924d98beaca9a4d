; Syntax highlighting of MCL.
;
; Portable across Neovim (nvim-treesitter), Helix and Zed: no predicates, and
; capture names that each editor either knows or falls back from to their
; parent (`@keyword.conditional` -> `@keyword` in Helix,
; `@constant.numeric` -> `@constant` in Neovim and Zed).

(comment) @comment

(string) @string

(import
  path: (string) @string.special.path)

(pattern_file
  path: (_) @string.special.path)

(number) @constant.numeric

; Keywords ------------------------------------------------------------------

[
  "actions"
  "events"
  "pattern"
  "patterns"
  "tasks"
  "mission"
  "mcl_plan_op"
  "constraints"
  "places"
  "transitions"
  "arcs"
] @keyword

"import" @keyword.import

[
  "if"
  "then"
  "else"
] @keyword.conditional

[
  "while"
  "do"
] @keyword.repeat

[
  "try"
  "catch"
] @keyword.exception

[
  "parallel"
  "monitor"
  "condition"
  "while_condition"
] @keyword.control

[
  "and"
  "or"
  "not"
] @keyword.operator

; Contextual words: only keywords where the grammar expects them.
[
  "c"
  "v"
  "a"
  "e"
  "at"
] @keyword

[
  "mutex"
  "_mutex_"
  "order"
  "_order_"
  "sync"
  "_sync_"
] @keyword

; Definitions ---------------------------------------------------------------

(action
  name: (identifier) @function)

(action
  primitive: (identifier) @constructor)

(command
  name: (identifier) @constant)

(parameter
  value: (identifier) @variable.parameter)

(event
  name: (identifier) @constant)

(pattern
  name: (identifier) @type)

(pattern_file
  name: (identifier) @type)

(place
  name: (identifier) @variable)

(transition
  name: (identifier) @variable.member)

(transition
  delay: (identifier) @variable.parameter)

(node_ref
  name: (identifier) @variable)

(interface
  (number) @constant.numeric)

(task
  name: (identifier) @function)

(task
  pattern: (identifier) @type)

(parameters
  (identifier) @variable.parameter)

(binding
  kind: "a"
  target: (identifier) @function)

(binding
  kind: "e"
  target: (identifier) @constant)

(binding
  transition: (identifier) @variable.member)

(mission
  name: (identifier) @module)

(placement
  id: (identifier) @variable)

; Statements ----------------------------------------------------------------

(call
  name: (identifier) @function.call)

(call
  label: (identifier) @label)

(list
  tag: (identifier) @type)

(label_ref
  mission: (identifier) @module)

(label_ref
  label: (identifier) @label)

; Punctuation ---------------------------------------------------------------

[
  "->"
  "→"
  "="
] @operator

[
  "{"
  "}"
  "("
  ")"
  "["
  "]"
] @punctuation.bracket

[
  ";"
  ","
  ":"
  "."
] @punctuation.delimiter

; Planning (`planning { ... }`, `pddl_map { ... }`) ---------------------------

[
  "planning"
  "pddl_map"
  "type"
  "entity"
  "function"
  "operator"
  "precond"
  "add"
  "del"
  "expression"
  "cost"
  "mcl"
  "initial"
  "goal"
] @keyword

(plan_type
  name: (identifier) @type)

(plan_entity
  type: (identifier) @type
  name: (identifier) @variable)

(plan_operator
  name: (identifier) @function)

(typed_parameter
  type: (identifier) @type
  name: (identifier) @variable.parameter)

(mission_call
  name: (identifier) @function)

(mapping
  action: (identifier) @function)

(attribute
  name: (identifier) @variable.member)
