-- MCL support for Neovim: the language server (`mcl lsp`) and the
-- tree-sitter parser of editors/tree-sitter-mcl. See editors/nvim/README.md.
--
--   require('mcl').setup({
--     cmd = { 'mcl', 'lsp' },          -- how to start the language server
--     lsp = true,                      -- start it for every MCL buffer
--     treesitter = true,               -- register the parser with nvim-treesitter
--     grammar = nil,                   -- editors/tree-sitter-mcl (found from this file by default)
--     ros2_bridge = nil,               -- a ROS 2 bridge file to check (docs/ros2.md), e.g. 'BRIDGE.toml'
--   })

local M = {}

local defaults = {
  cmd = { 'mcl', 'lsp' },
  lsp = true,
  treesitter = true,
  grammar = nil,
  root_markers = { '.git' },
}

--- editors/tree-sitter-mcl, found from this file (editors/nvim/lua/mcl/init.lua).
local function default_grammar()
  local here = debug.getinfo(1, 'S').source:sub(2)
  local editors = vim.fn.fnamemodify(here, ':p:h:h:h:h')
  return editors .. '/tree-sitter-mcl'
end

local uv = vim.uv or vim.loop

--- The nearest ancestor directory of `buf`'s file holding one of `markers`,
--- else the file's own directory. Works from Neovim 0.7 (no `vim.fs` there).
local function root_dir(buf, markers)
  local name = vim.api.nvim_buf_get_name(buf)
  if vim.fs and vim.fs.root then
    return vim.fs.root(buf, markers) or vim.fs.dirname(name)
  end
  local start = vim.fn.fnamemodify(name, ':p:h')
  local dir = start
  while dir and dir ~= '' do
    for _, marker in ipairs(markers) do
      if uv.fs_stat(dir .. '/' .. marker) then
        return dir
      end
    end
    local parent = vim.fn.fnamemodify(dir, ':h')
    if parent == dir then
      break
    end
    dir = parent
  end
  return start
end

local function warn_once(msg)
  if vim.notify_once then
    vim.notify_once(msg, vim.log.levels.WARN)
  else
    vim.notify(msg, vim.log.levels.WARN)
  end
end

--- Starts (or reuses) the MCL language server for `buf`.
function M.start_lsp(buf, opts)
  opts = opts or M.options or defaults
  if vim.fn.executable(opts.cmd[1]) ~= 1 then
    warn_once(('mcl: `%s` not found; install it with `cargo install --path .` in the MCL repository'):format(opts.cmd[1]))
    return
  end
  local config = { name = 'mcl', cmd = opts.cmd, root_dir = root_dir(buf, opts.root_markers) }
  if opts.ros2_bridge then
    config.init_options = { ros2Bridge = opts.ros2_bridge }
  end
  if vim.lsp.start then
    return vim.lsp.start(config, { bufnr = buf })
  end
  -- Neovim 0.7 (Debian 12's package): no `vim.lsp.start`; reuse the client
  -- of the same root, or start one, and attach the buffer to it.
  for _, client in pairs(vim.lsp.get_active_clients()) do
    if client.name == 'mcl' and client.config.root_dir == config.root_dir and not client.is_stopped() then
      vim.lsp.buf_attach_client(buf, client.id)
      return client.id
    end
  end
  local id = vim.lsp.start_client(config)
  if id then
    vim.lsp.buf_attach_client(buf, id)
  end
  return id
end

--- Registers the parser with nvim-treesitter (both its `main` and `master` branches).
function M.register_parser(grammar)
  grammar = grammar or default_grammar()
  local ok, parsers = pcall(require, 'nvim-treesitter.parsers')
  if not ok then
    return false
  end
  if type(parsers.get_parser_configs) == 'function' then
    -- nvim-treesitter `master`: `:TSInstall mcl` compiles src/parser.c.
    parsers.get_parser_configs().mcl = {
      install_info = { url = grammar, files = { 'src/parser.c' }, generate_requires_npm = false, requires_generate_from_grammar = false },
      filetype = 'mcl',
    }
  else
    -- nvim-treesitter `main`: `:TSInstall mcl` after each `TSUpdate` event.
    local function add()
      require('nvim-treesitter.parsers').mcl = {
        install_info = { path = grammar, generate = false, queries = 'queries' },
      }
    end
    add()
    vim.api.nvim_create_autocmd('User', { pattern = 'TSUpdate', callback = add })
  end
  if vim.treesitter.language and vim.treesitter.language.register then
    vim.treesitter.language.register('mcl', 'mcl')
  end
  return true
end

--- `*.mcl` files get the `mcl` filetype. Neovim 0.7 only uses the Lua
--- filetype table when `do_filetype_lua` is set, so add an autocommand there.
function M.detect_filetype()
  vim.filetype.add({ extension = { mcl = 'mcl' } })
  if vim.fn.has('nvim-0.8') == 0 then
    vim.api.nvim_create_autocmd({ 'BufNewFile', 'BufRead' }, {
      group = vim.api.nvim_create_augroup('mcl-filetype', { clear = true }),
      pattern = '*.mcl',
      command = 'setfiletype mcl',
    })
  end
end

function M.setup(opts)
  M.options = vim.tbl_deep_extend('force', defaults, opts or {})
  M.detect_filetype()
  if M.options.treesitter then
    M.register_parser(M.options.grammar)
  end
  if M.options.treesitter then
    -- Highlighting, folding and indentation from the queries, when the
    -- parser is installed (`:TSInstall mcl`).
    vim.api.nvim_create_autocmd('FileType', {
      group = vim.api.nvim_create_augroup('mcl-treesitter', { clear = true }),
      pattern = 'mcl',
      callback = function(args)
        pcall(vim.treesitter.start, args.buf, 'mcl')
      end,
    })
  end
  if M.options.lsp then
    local group = vim.api.nvim_create_augroup('mcl-lsp', { clear = true })
    vim.api.nvim_create_autocmd('FileType', {
      group = group,
      pattern = 'mcl',
      callback = function(args)
        M.start_lsp(args.buf)
      end,
    })
  end
end

return M
