-- The end-to-end test's script (cli/tests/cli/editor.rs): headless Neovim
-- (0.7 or later) opens $MODEL, starts `$LEEWAY lsp` as its language
-- server, waits for the diagnostics, asks for a hover at $HOVER
-- ("line:character", 0-based) and a format, and writes what it holds to $OUT.
local leeway, model, out = os.getenv('LEEWAY'), os.getenv('MODEL'), os.getenv('OUT')
local hl, hc = os.getenv('HOVER'):match('(%d+):(%d+)')
local lines = {}
local function say(s) table.insert(lines, s) end

vim.cmd('edit ' .. vim.fn.fnameescape(model))
local buf = vim.api.nvim_get_current_buf()
local id = vim.lsp.start_client({ name = 'leeway', cmd = { leeway, 'lsp' }, root_dir = vim.fn.getcwd() })
vim.lsp.buf_attach_client(buf, id)

if not vim.wait(30000, function() return #vim.diagnostic.get(buf) > 0 end, 20) then
  say('no diagnostics received')
end
local found = {}
for _, d in ipairs(vim.diagnostic.get(buf)) do
  local lsp = (d.user_data or {}).lsp or {}
  local code = d.code or lsp.code or ''
  table.insert(found, string.format('diagnostic %d:%d severity %d [%s] %s',
    d.lnum + 1, d.col + 1, d.severity, code, (d.message:gsub('\n.*', ''))))
end
table.sort(found)
for _, f in ipairs(found) do say(f) end

local params = { textDocument = { uri = vim.uri_from_bufnr(buf) },
                 position = { line = tonumber(hl), character = tonumber(hc) } }
local answers = vim.lsp.buf_request_sync(buf, 'textDocument/hover', params, 30000) or {}
for _, a in pairs(answers) do
  if a.result and a.result.contents then
    say('hover: ' .. (a.result.contents.value:gsub('\n+', ' | ')))
  end
end

if vim.lsp.buf.format then
  vim.lsp.buf.format({ timeout_ms = 30000 })
else
  vim.lsp.buf.formatting_sync(nil, 30000)
end
say('--- the buffer after formatting')
for _, l in ipairs(vim.api.nvim_buf_get_lines(buf, 0, -1, false)) do say(l) end

vim.fn.writefile(lines, out)
vim.lsp.stop_client(id)
vim.cmd('qall!')
