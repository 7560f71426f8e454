-- leeway's language server in Neovim (0.7 or later), no plugin needed.
-- Put this file in ~/.config/nvim/plugin/ (or `:luafile` it); set
-- LEEWAY to the binary if `leeway` is not on PATH. K shows the hover,
-- gd goes to the definition, gr lists references, <space>f formats.
vim.cmd([[autocmd BufRead,BufNewFile *.som setfiletype som]])

local leeway = os.getenv('LEEWAY') or 'leeway'

vim.api.nvim_create_autocmd('FileType', {
  pattern = 'som',
  callback = function(args)
    vim.bo[args.buf].commentstring = '// %s'
    local root = vim.fn.fnamemodify(vim.api.nvim_buf_get_name(args.buf), ':p:h')
    local id = vim.lsp.start_client({ name = 'leeway', cmd = { leeway, 'lsp' }, root_dir = root })
    if not id then return end
    vim.lsp.buf_attach_client(args.buf, id)
    local map = function(keys, f) vim.keymap.set('n', keys, f, { buffer = args.buf }) end
    map('K', vim.lsp.buf.hover)
    map('gd', vim.lsp.buf.definition)
    map('gr', vim.lsp.buf.references)
    map('<space>f', function()
      if vim.lsp.buf.format then vim.lsp.buf.format() else vim.lsp.buf.formatting_sync() end
    end)
  end,
})
