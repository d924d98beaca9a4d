-- `.mcl` files are MCL missions.
vim.filetype.add({ extension = { mcl = 'mcl' } })
