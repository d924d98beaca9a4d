; Folding (Neovim): every braced block and every multi-line comment.

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
  (mission)
  (block)
  (condition)
  (constraints_block)
  (comment)
] @fold
