#!/usr/bin/env bash
# The screenshots of docs/editor.md: Neovim (with leeway.lua) in a tmux
# pane, a broken model open; one capture with the diagnostics, one with the
# hover on a term. Usage: screenshots.sh LEEWAY_BINARY OUT_DIR (needs tmux,
# nvim, and a Python with Pillow: PYTHON=/path/to/python to choose it).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
leeway="$(realpath "$1")"; out="$(realpath "$2")"
work="$(mktemp -d)"; trap 'tmux kill-session -t leeway-shot 2>/dev/null || true; sleep 1; rm -rf "$work" 2>/dev/null || true' EXIT
cp "$here/../../examples/models/rov.som" "$work/rov.som"
cols=120; rows=34
cd "$work"
tmux new-session -d -s leeway-shot -x $cols -y $rows \
  "env TERM=xterm-256color LEEWAY=$leeway HOME=$work nvim -n -u $here/leeway.lua rov.som"
sleep 3
# A mistake typed in: a term beyond second order in the sway equation.
tmux send-keys -t leeway-shot ':19' Enter 'A + Y_3*v*v*v' Escape
sleep 2
tmux capture-pane -t leeway-shot -e -p > diagnostics.txt
"${PYTHON:-python3}" "$here/ansi2png.py" diagnostics.txt "$out/nvim-diagnostics.png" $cols $rows
# Undone; the hover on the term `Y_vv*water.v*|water.v|` of line 18.
tmux send-keys -t leeway-shot 'u'
sleep 1
tmux send-keys -t leeway-shot ':call cursor(18, 33)' Enter 'K'
sleep 2
tmux capture-pane -t leeway-shot -e -p > hover.txt
"${PYTHON:-python3}" "$here/ansi2png.py" hover.txt "$out/nvim-hover.png" $cols $rows
