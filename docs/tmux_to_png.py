"""Render a ``tmux capture-pane -p -e`` text capture (ANSI SGR colours) to a PNG with PIL.

    tmux capture-pane -t SESSION -p -e > capture.txt
    python docs/tmux_to_png.py capture.txt docs/watch_live.png
"""

from __future__ import annotations

import re
import sys

from PIL import Image, ImageDraw, ImageFont

FONT = "/usr/share/fonts/truetype/dejavu/DejaVuSansMono.ttf"
FONT_BOLD = "/usr/share/fonts/truetype/dejavu/DejaVuSansMono-Bold.ttf"
BG, FG = (24, 24, 28), (220, 220, 220)
BASIC = [(0, 0, 0), (220, 60, 60), (80, 200, 90), (220, 200, 80), (90, 140, 230),
         (200, 100, 200), (80, 200, 210), (220, 220, 220)]
SGR = re.compile(r"\x1b\[([0-9;]*)m")


def render(text: str, out: str, size: int = 15) -> None:
    font = ImageFont.truetype(FONT, size)
    bold = ImageFont.truetype(FONT_BOLD, size)
    cw = int(font.getlength("M"))
    ch = sum(font.getmetrics())
    lines = text.rstrip("\n").split("\n")
    while lines and not SGR.sub("", lines[-1]).strip():
        lines.pop()
    width = max(len(SGR.sub("", ln)) for ln in lines)
    img = Image.new("RGB", (cw * width + 24, ch * len(lines) + 24), BG)
    draw = ImageDraw.Draw(img)
    for row, line in enumerate(lines):
        col, fg, is_bold, dim = 0, FG, False, False
        pos = 0
        for m in list(SGR.finditer(line)) + [None]:
            end = m.start() if m else len(line)
            chunk = line[pos:end]
            colour = tuple(c // 2 for c in fg) if dim else fg
            for c in chunk:
                draw.text((12 + col * cw, 12 + row * ch), c, fill=colour,
                          font=bold if is_bold else font)
                col += 1
            if m is None:
                break
            pos = m.end()
            codes = [int(x) for x in m.group(1).split(";") if x] or [0]
            i = 0
            while i < len(codes):
                k = codes[i]
                if k == 0:
                    fg, is_bold, dim = FG, False, False
                elif k == 1:
                    is_bold = True
                elif k == 2:
                    dim = True
                elif k == 22:
                    is_bold = dim = False
                elif 30 <= k <= 37:
                    fg = BASIC[k - 30]
                elif 90 <= k <= 97:
                    fg = BASIC[k - 90]
                elif k == 39:
                    fg = FG
                elif k == 38 and i + 2 < len(codes) and codes[i + 1] == 5:
                    n = codes[i + 2]
                    fg = BASIC[n % 8] if n < 16 else FG
                    i += 2
                i += 1
    img.save(out)


if __name__ == "__main__":
    render(open(sys.argv[1], encoding="utf-8").read(), sys.argv[2])
