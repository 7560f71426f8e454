// The client: starts `leeway lsp` (the binary named by the `leeway.path`
// setting) for every `.som` file; everything else is the server's.
const vscode = require('vscode');
const { LanguageClient } = require('vscode-languageclient/node');

let client;

function activate(context) {
  const command = vscode.workspace.getConfiguration('leeway').get('path') || 'leeway';
  const server = { command, args: ['lsp'] };
  client = new LanguageClient(
    'leeway',
    'leeway',
    { run: server, debug: server },
    { documentSelector: [{ language: 'som' }] }
  );
  context.subscriptions.push(client);
  return client.start();
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
