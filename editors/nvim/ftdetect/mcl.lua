-- `.mcl` files are MCL missions.
vim.filetype.add({ extension = { mcl = 'mcl' } })
if vim.fn.has('nvim-0.8') == 0 then
  -- Neovim 0.7 reads the Lua filetype table only with `do_filetype_lua`.
  vim.cmd('autocmd BufNewFile,BufRead *.mcl setfiletype mcl')
end
