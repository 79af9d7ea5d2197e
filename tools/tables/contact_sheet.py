"""Pastes pictures into one sheet, one row per group, left to right and top to bottom.

    python3 tools/tables/contact_sheet.py OUT.png "a.png b.png ..." "c.png d.png ..."

Each argument after OUT.png is one row: picture paths separated by white space. An
empty row is skipped. Needs Pillow.
"""
import sys

from PIL import Image


def main(out, rows):
    rows = [[Image.open(p) for p in row.split()] for row in rows]
    rows = [r for r in rows if r]
    if not rows:
        sys.exit("contact_sheet.py: no pictures")
    width = max(sum(i.width for i in r) for r in rows)
    height = sum(max(i.height for i in r) for r in rows)
    sheet = Image.new("RGB", (width, height), "white")
    y = 0
    for r in rows:
        x = 0
        for i in r:
            sheet.paste(i, (x, y))
            x += i.width
        y += max(i.height for i in r)
    sheet.save(out)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
