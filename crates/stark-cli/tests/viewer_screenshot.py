"""The HTML viewer shows the scene in a real browser: run a short contact scene, write its
viewer with `stark view`, take a screenshot with headless Chromium (software WebGL) and check
that the objects' colours cover part of the picture (not a blank or an error page).

Usage: viewer_screenshot.py CHROMIUM STARK_BINARY   (run by ./test.sh when a browser exists)
"""

import struct
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path


def png_pixels(path):
    """(width, height, rows of RGB(A) bytes) of an 8-bit RGB or RGBA PNG, without PIL."""
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, chunks = 8, {}
    idat = b""
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            chunks["IHDR"] = body
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour = struct.unpack(">IIBB", chunks["IHDR"][:10])
    assert depth == 8 and colour in (2, 6), f"unexpected PNG format {depth}/{colour}"
    bpp = 3 if colour == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * bpp
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, bpp, rows


def main():
    browser, stark = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        subprocess.run([stark, "run", "--scene", "soft_cubes", "--duration", "0.2", "--quiet", "--no-plot",
                        "--out", str(out)], check=True, stdout=subprocess.DEVNULL)
        html = Path(tmp) / "view.html"
        subprocess.run([stark, "view", str(out), "-o", str(html)], check=True, stdout=subprocess.DEVNULL)
        shot = Path(tmp) / "shot.png"
        profile = Path(tmp) / "profile"
        profile.mkdir()
        subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                        "--disable-component-update", "--disable-sync", "--no-first-run",
                        f"--user-data-dir={profile}", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                        "--window-size=900,600", "--virtual-time-budget=8000", f"--screenshot={shot}",
                        html.as_uri() + "#field=von_mises_pa&frame=last"],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=180)
        width, height, bpp, rows = png_pixels(shot)
        # Saturated pixels below the toolbar: the objects (the background and UI are grey).
        coloured = 0
        for y in range(60, height - 40):
            row = rows[y]
            for x in range(width):
                r, g, b = row[bpp * x:bpp * x + 3]
                if max(r, g, b) - min(r, g, b) > 60:
                    coloured += 1
        share = coloured / (width * (height - 100))
        print(f"viewer screenshot: {width}×{height}, {100 * share:.1f}% of the view shows coloured objects")
        assert share > 0.02, "the viewer's screenshot shows no objects"


if __name__ == "__main__":
    main()
