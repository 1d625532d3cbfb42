"""Build the site and look at it as a reader does: every page in headless Chromium at 1280 px.

``python docs/screenshot.py [--out DIR] [--width 1280] [--page NAME ...]`` builds the site
(``mkdocs build --strict``) into a temporary folder, serves it on a local port, opens each page
in headless Chromium at the given window width, saves a full-page PNG per page into ``--out``
(default: ``camjax-site-shots`` in the temporary folder) and reports, page by page:

- a page that scrolls sideways (the document wider than the window);
- a table wider than its box (a horizontal scroll bar of its own);
- a figure shown narrower than 90 % of its own width while the column had room for it (its
  title block would be too small to read).

It exits 1 when a page has one of these, 0 otherwise, and 2 when no Chromium is found. It needs
only a Chromium binary, run as a command line (``--dump-dom`` and ``--screenshot``): on Debian
``apt-get install chromium-headless-shell`` (or ``chromium``), elsewhere any Chrome or Chromium
(``--chromium PATH``). The measurements are made by a script the local server adds to each page
as it serves it; the built site is not changed. A development tool, not a dependency of camjax:
CI builds the site strictly but does not take screenshots.
"""

from __future__ import annotations

import argparse
import functools
import http.server
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BROWSERS = ("chromium-headless-shell", "chrome-headless-shell", "chromium", "chromium-browser",
            "google-chrome", "google-chrome-stable")

# Added to each served page: on load, measure what overflows and leave it as JSON in a hidden
# element for --dump-dom to print.
CHECK = """<script>
window.addEventListener('load', () => {
  const width = window.innerWidth;
  const out = {page_width: document.documentElement.scrollWidth,
               page_height: document.documentElement.scrollHeight, tables: [], figures: []};
  for (const t of document.querySelectorAll('.md-typeset table')) {
    const box = t.closest('.md-typeset__table') || t.parentElement;
    if (t.scrollWidth > box.clientWidth + 1) {
      const head = t.querySelector('th');
      out.tables.push({header: head ? head.innerText.slice(0, 60) : '', width: t.scrollWidth,
                       room: box.clientWidth});
    }
  }
  const column = document.querySelector('.md-content__inner');
  const room = column ? column.clientWidth : width;
  for (const img of document.querySelectorAll('.md-typeset img')) {
    if (!img.naturalWidth || img.closest('.thumbs')) continue;
    if (img.clientWidth < 0.9 * Math.min(img.naturalWidth, room)) {
      out.figures.push({src: img.getAttribute('src'), shown: img.clientWidth, natural: img.naturalWidth});
    }
  }
  const pre = document.createElement('pre');
  pre.id = 'camjax-layout';
  pre.style.display = 'none';
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>"""


def build(site: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(site)],
                   cwd=ROOT, env=env, check=True)


def pages(site: Path) -> list[str]:
    """Every page of the built site, as a path under its root ('' for the home page)."""
    return sorted("" if p.parent == site else p.parent.relative_to(site).as_posix() + "/"
                  for p in site.rglob("index.html"))


def serve(site: Path) -> tuple[http.server.ThreadingHTTPServer, str]:
    """Serve ``site`` on a free local port, each page with :data:`CHECK` added before ``</body>``."""

    class Handler(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):  # no line per request
            pass

        def send_head(self):
            path = Path(self.translate_path(self.path))
            if path.is_dir():
                path = path / "index.html"
            if path.suffix != ".html" or not path.is_file():
                return super().send_head()
            body = path.read_text(encoding="utf-8").replace("</body>", CHECK + "</body>", 1).encode()
            self.send_response(200)
            self.send_header("Content-Type", "text/html; charset=utf-8")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            return io.BytesIO(body)

    handler = functools.partial(Handler, directory=str(site))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server, f"http://127.0.0.1:{server.server_address[1]}/"


def chromium(browser: str, *args: str, timeout: float = 60) -> str:
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
           "--virtual-time-budget=8000", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout).stdout


def measure(browser: str, url: str, width: int) -> dict:
    """What :data:`CHECK` found on the page at ``url`` in a window ``width`` px wide."""
    dom = chromium(browser, f"--window-size={width},900", "--dump-dom", url)
    m = re.search(r'<pre id="camjax-layout"[^>]*>(.*?)</pre>', dom, flags=re.S)
    if not m:
        raise RuntimeError(f"{url}: the page's layout check did not run")
    return json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&").replace("&lt;", "<")
                      .replace("&gt;", ">"))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "camjax-site-shots",
                        help="folder for the PNGs (default: camjax-site-shots in the temporary folder)")
    parser.add_argument("--width", type=int, default=1280, help="window width in px (default 1280)")
    parser.add_argument("--page", action="append",
                        help="only this page, as its path ('performance', 'api/scenes'; repeatable)")
    parser.add_argument("--chromium", help="the Chromium or Chrome binary (default: the first of "
                        + ", ".join(BROWSERS) + " on PATH)")
    args = parser.parse_args(argv)
    browser = args.chromium or next((b for b in map(shutil.which, BROWSERS) if b), None)
    if not browser:
        print("docs/screenshot.py needs a Chromium binary: apt-get install chromium-headless-shell "
              "(Debian), or --chromium PATH", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        site = Path(tmp) / "site"
        build(site)
        names = [p for p in pages(site) if not args.page or p.strip("/") in args.page]
        server, url = serve(site)
        args.out.mkdir(parents=True, exist_ok=True)
        problems = 0
        try:
            for name in names:
                found = measure(browser, url + name, args.width)
                shot = args.out / f"{name.strip('/').replace('/', '_') or 'index'}.png"
                height = min(int(found["page_height"]), 16000)
                chromium(browser, f"--window-size={args.width},{height}", f"--screenshot={shot}", url + name)
                lines = []
                if found["page_width"] > args.width:
                    lines.append(f"page scrolls sideways: {found['page_width']} px")
                lines += [f"table '{t['header']}' {t['width']} px in {t['room']} px" for t in found["tables"]]
                lines += [f"figure {f['src']} shown {f['shown']} of {f['natural']} px"
                          for f in found["figures"]]
                problems += bool(lines)
                verdict = "; ".join(lines) if lines else "ok"
                print(f"{name or '/'}: {verdict} ({shot.name})", flush=True)
        finally:
            server.shutdown()
    print(f"{len(names)} pages, {problems} with a problem; screenshots in {args.out}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
