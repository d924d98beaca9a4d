-- Headless Neovim driver for tests/nvim.rs: loads the plugin in
-- editors/nvim exactly as a user would (runtimepath + setup), opens the file
-- given on the command line, waits for the language server's diagnostics and
-- writes what Neovim received to $MCL_NVIM_OUT as JSON, then quits.
local out = assert(os.getenv('MCL_NVIM_OUT'), 'MCL_NVIM_OUT not set')
local plugin = assert(os.getenv('MCL_NVIM_PLUGIN'), 'MCL_NVIM_PLUGIN not set')
local timeout = tonumber(os.getenv('MCL_NVIM_TIMEOUT_MS') or '60000')

vim.opt.runtimepath:prepend(plugin)
vim.cmd('runtime! ftdetect/*.lua')
require('mcl').setup({ treesitter = false })

local function write(result)
  local f = assert(io.open(out, 'w'))
  f:write(vim.fn.json_encode(result))
  f:close()
end

local function finish()
  local buf = vim.api.nvim_get_current_buf()
  local received = vim.wait(timeout, function()
    return #vim.diagnostic.get(buf) > 0
  end, 50)
  local diagnostics = {}
  for _, d in ipairs(vim.diagnostic.get(buf)) do
    local code = d.code
    if code == nil and d.user_data and d.user_data.lsp then
      code = d.user_data.lsp.code
    end
    table.insert(diagnostics, {
      lnum = d.lnum,
      col = d.col,
      end_lnum = d.end_lnum,
      severity = d.severity,
      message = d.message,
      source = d.source,
      code = code,
    })
  end
  -- Fix the typo as a user would: the change goes to the server
  -- (textDocument/didChange) and the diagnostics must go away.
  local cleared = false
  if received then
    local lines = vim.api.nvim_buf_get_lines(buf, 0, -1, false)
    for i, line in ipairs(lines) do
      if line:find('Surfaec', 1, true) then
        vim.api.nvim_buf_set_lines(buf, i - 1, i, false, { (line:gsub('Surfaec', 'Surface')) })
      end
    end
    cleared = vim.wait(timeout, function()
      return #vim.diagnostic.get(buf) == 0
    end, 50)
  end
  local clients = {}
  local get = vim.lsp.get_clients or vim.lsp.get_active_clients
  for _, c in pairs(get()) do
    table.insert(clients, c.name)
  end
  write({
    nvim = tostring(vim.version().major) .. '.' .. tostring(vim.version().minor),
    filetype = vim.bo[buf].filetype,
    clients = clients,
    timed_out = not received,
    cleared_after_fix = cleared,
    diagnostics = diagnostics,
  })
  vim.cmd('qall!')
end

vim.api.nvim_create_autocmd('VimEnter', { callback = function() vim.schedule(finish) end })
