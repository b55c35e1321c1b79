#!/usr/bin/env python3
"""Checks that the built book (book/build/) renders its formulas without a network.

1. No page of book/build loads a script, stylesheet or font from another host (a CDN).
2. Every chapter, opened from disk in headless Chromium with every host name unresolvable,
   shows no raw TeX in its rendered text (the DOM after loading, without the MathML
   annotations that keep each formula's source for screen readers, and without code blocks),
   and the model chapter holds rendered formulas.

Usage: python3 .ci/book_offline.py [--screenshot PATH]   (PATH: a PNG of the model chapter)
Needs Debian's `chromium` (as root it runs with --no-sandbox). Standard library only.
"""

import argparse
import html.parser
import pathlib
import re
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
BUILD = ROOT / "book" / "build"

CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    # Offline: no host name resolves, so anything fetched from a CDN would be missing.
    "--host-resolver-rules=MAP * ~NOTFOUND",
]

# A resource loaded from elsewhere: <script src="http...">, <link href="http..."> (stylesheet,
# preload, font), url(http...) in inline CSS. Plain links to other sites (<a href>) are fine.
EXTERNAL = re.compile(
    r"<script[^>]*\ssrc=\"(?:https?:)?//|<link[^>]*\shref=\"(?:https?:)?//|url\(\s*['\"]?(?:https?:)?//|mathjax",
    re.IGNORECASE,
)

# Raw TeX as a reader would see it when a formula is not rendered.
# A formula whose delimiters Markdown ate leaves its groups: `e^{-T/(R_L C_s)}`.
RAW_TEX = re.compile(r"\\[()\[\]]|\\(?:frac|mathrm|sqrt|left|right|delta|lambda|sum|dot|operatorname|text)\b|[\^_]\{")

SKIP = {"script", "style", "annotation", "code", "pre", "title", "noscript"}


class VisibleText(html.parser.HTMLParser):
    """Collects the text outside SKIP elements, and counts KaTeX's rendered formulas."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.depth = 0
        self.parts = []
        self.formulas = 0

    def handle_starttag(self, tag, attrs):
        if tag in SKIP:
            self.depth += 1
        if tag == "span" and ("class", "katex") in attrs:
            self.formulas += 1

    def handle_endtag(self, tag):
        if tag in SKIP and self.depth > 0:
            self.depth -= 1

    def handle_data(self, data):
        if self.depth == 0:
            self.parts.append(data)


def chromium(args, profile):
    cmd = ["chromium", *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    if out.returncode != 0:
        sys.exit(f"chromium failed ({out.returncode}): {out.stderr[-2000:]}")
    return out.stdout


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--screenshot", help="write a PNG of the model chapter here")
    a = ap.parse_args()
    pages = sorted(BUILD.glob("**/*.html"))
    if not (BUILD / "model.html").exists():
        sys.exit("book/build/model.html is missing: build the book first")
    failures = []
    for page in pages:
        for m in EXTERNAL.finditer(page.read_text(encoding="utf-8")):
            failures.append(f"{page.relative_to(ROOT)}: loads from elsewhere: {m.group(0)!r}")
    chapters = [p for p in pages if p.name not in ("404.html", "print.html", "toc.html")]
    with tempfile.TemporaryDirectory() as tmp:
        for i, page in enumerate(chapters):
            dom = chromium(["--dump-dom", page.as_uri()], pathlib.Path(tmp) / f"p{i}")
            text = VisibleText()
            text.feed(dom)
            visible = "".join(text.parts)
            raw = sorted({m.group(0) for m in RAW_TEX.finditer(visible)})
            if raw:
                failures.append(f"{page.name}: raw TeX in the rendered text: {raw}")
            if page.name == "model.html" and text.formulas == 0:
                failures.append("model.html: no rendered formula")
            print(f"{page.name}: {text.formulas} formulas rendered, no raw TeX" if not raw else f"{page.name}: RAW TeX {raw}")
        if a.screenshot:
            chromium(
                ["--window-size=1100,1800", f"--screenshot={pathlib.Path(a.screenshot).resolve()}",
                 (BUILD / "model.html").as_uri()],
                pathlib.Path(tmp) / "shot",
            )
    if failures:
        print("\n".join(failures), file=sys.stderr)
        sys.exit(1)
    print(f"book offline check: {len(pages)} pages without external resources, "
          f"{len(chapters)} chapters without raw TeX")


if __name__ == "__main__":
    main()
