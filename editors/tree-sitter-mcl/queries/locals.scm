; Scopes, definitions and references (Neovim and Helix).

; A task's parameters are seen by its bindings; a mission's by its calls; a
; pattern's places and transitions by its arcs.
[
  (task)
  (mission)
  (pattern)
] @local.scope

(task
  parameters: (parameters
    (identifier) @local.definition))

(mission
  parameters: (parameters
    (identifier) @local.definition))

(place
  name: (identifier) @local.definition)

(transition
  name: (identifier) @local.definition)

(node_ref
  name: (identifier) @local.reference)

(transition
  delay: (identifier) @local.reference)

(binding
  transition: (identifier) @local.reference)

(arguments
  (identifier) @local.reference)

(list
  (identifier) @local.reference)
