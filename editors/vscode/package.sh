#!/usr/bin/env bash
# Packages the extension as leeway-som-VERSION.vsix with the npm registry's
# tools (@vscode/vsce and vscode-languageclient, pinned in package.json);
# needs node (18 or later) and npm. Install the result with
# `code --install-extension leeway-som-VERSION.vsix`. `npm test` (after
# `npm install`) checks the TextMate grammar on the example models.
set -euo pipefail
cd "$(dirname "$0")"
npm install --no-audit --no-fund --loglevel=error
version="$(node -p "require('./package.json').version")"
npx --no-install vsce package --skip-license -o "leeway-som-$version.vsix"
