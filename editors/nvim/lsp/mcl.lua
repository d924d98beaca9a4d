-- The MCL language server, for Neovim >= 0.11: with editors/nvim on the
-- runtimepath, `vim.lsp.enable('mcl')` starts it for every MCL buffer.
return {
  cmd = { 'mcl', 'lsp' },
  filetypes = { 'mcl' },
  root_markers = { '.git' },
}
