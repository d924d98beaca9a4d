-- Buffer settings for MCL: the canonical style of `mcl fmt` (4 spaces), and
-- `gq` formats through `mcl fmt -` when the language server is not attached.
if vim.b.did_ftplugin then
  return
end
vim.b.did_ftplugin = true

vim.bo.commentstring = '// %s'
vim.bo.comments = 's1:/*,mb:*,ex:*/,://'
vim.bo.expandtab = true
vim.bo.shiftwidth = 4
vim.bo.softtabstop = 4
vim.bo.tabstop = 4
vim.bo.formatprg = 'mcl fmt -'
vim.bo.iskeyword = '@,48-57,_,$,-,/'

vim.b.undo_ftplugin = 'setlocal commentstring< comments< expandtab< shiftwidth< softtabstop< tabstop< formatprg< iskeyword<'
