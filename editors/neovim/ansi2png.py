#!/usr/bin/env python3
"""Renders a terminal capture (`tmux capture-pane -e -p`: text with SGR
colour codes) to a PNG, cell by cell in DejaVu Sans Mono: the screenshots
of docs/editor.md. Usage: ansi2png.py CAPTURE.txt OUT.png COLUMNS ROWS"""
import re
import sys

from PIL import Image, ImageDraw, ImageFont

FONT = "/usr/share/fonts/truetype/dejavu/DejaVuSansMono.ttf"
BASE = [(0, 0, 0), (205, 49, 49), (13, 188, 121), (229, 229, 16), (36, 114, 200),
        (188, 63, 188), (17, 168, 205), (229, 229, 229)]
BRIGHT = [(102, 102, 102), (241, 76, 76), (35, 209, 139), (245, 245, 67), (59, 142, 234),
          (214, 112, 214), (41, 184, 219), (255, 255, 255)]
FG, BG = (220, 220, 220), (24, 24, 24)


def xterm256(n):
    if n < 8:
        return BASE[n]
    if n < 16:
        return BRIGHT[n - 8]
    if n < 232:
        n -= 16
        steps = [0, 95, 135, 175, 215, 255]
        return (steps[n // 36], steps[(n // 6) % 6], steps[n % 6])
    g = 8 + 10 * (n - 232)
    return (g, g, g)


def sgr(params, state):
    fg, bg, rev = state
    codes = [int(p) if p else 0 for p in params.split(";")] if params else [0]
    i = 0
    while i < len(codes):
        c = codes[i]
        if c == 0:
            fg, bg, rev = FG, BG, False
        elif c == 7:
            rev = True
        elif c == 27:
            rev = False
        elif 30 <= c <= 37:
            fg = BASE[c - 30]
        elif 90 <= c <= 97:
            fg = BRIGHT[c - 90]
        elif 40 <= c <= 47:
            bg = BASE[c - 40]
        elif 100 <= c <= 107:
            bg = BRIGHT[c - 100]
        elif c == 39:
            fg = FG
        elif c == 49:
            bg = BG
        elif c in (38, 48) and i + 1 < len(codes):
            if codes[i + 1] == 5 and i + 2 < len(codes):
                colour = xterm256(codes[i + 2])
                i += 2
            elif codes[i + 1] == 2 and i + 4 < len(codes):
                colour = tuple(codes[i + 2:i + 5])
                i += 4
            else:
                colour = FG if c == 38 else BG
            if c == 38:
                fg = colour
            else:
                bg = colour
        i += 1
    return fg, bg, rev


def main():
    capture, out, cols, rows = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    font = ImageFont.truetype(FONT, 16)
    cw = int(font.getlength("M"))
    ch = 20
    img = Image.new("RGB", (cols * cw + 16, rows * ch + 16), BG)
    draw = ImageDraw.Draw(img)
    state = (FG, BG, False)
    lines = open(capture, encoding="utf-8").read().split("\n")[:rows]
    for y, line in enumerate(lines):
        x = 0
        for token in re.split(r"(\x1b\[[0-9;]*m)", line):
            m = re.fullmatch(r"\x1b\[([0-9;]*)m", token)
            if m:
                state = sgr(m.group(1), state)
                continue
            for char in token:
                fg, bg, rev = state
                if rev:
                    fg, bg = bg, fg
                px, py = 8 + x * cw, 8 + y * ch
                draw.rectangle([px, py, px + cw, py + ch], fill=bg)
                draw.text((px, py + 1), char, font=font, fill=fg)
                x += 1
    img.save(out)


if __name__ == "__main__":
    main()
