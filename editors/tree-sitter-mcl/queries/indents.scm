; Indentation. The captures of several editors live side by side; each one
; ignores the names it does not know:
;   Neovim (nvim-treesitter): @indent.begin, @indent.branch, @indent.end
;   Helix: @indent, @outdent
;   Zed: @indent, @end

; Neovim --------------------------------------------------------------------

[
  (actions_block)
  (events_block)
  (patterns_block)
  (pattern)
  (places)
  (transitions)
  (arcs)
  (tasks_block)
  (task)
  (block)
  (condition)
  (arguments)
  (list)
  (constraints_block)
  (constraint)
] @indent.begin

[
  "}"
  ")"
  "]"
] @indent.branch @indent.end

(comment) @indent.auto

; Helix and Zed ---------------------------------------------------------------

; Whatever is between a pair of brackets is indented one level.
(_ "{" "}" @end) @indent
(_ "(" ")" @end) @indent
(_ "[" "]" @end) @indent

; Helix: a closing bracket goes back one level.
[
  "}"
  ")"
  "]"
] @outdent
