"""Make the FORD site work offline (clusters often have no internet access).

FORD 7 writes pages that load Bootstrap 5.3.3 and MathJax 2.7.9 from a CDN and, for the
search page, lunr.js from another; without a network the site is unstyled and search is
dead. This script, run by scripts/docs.sh after FORD, copies the vendored files of
docs/ford_assets/ (Bootstrap 5.3.3 and lunr 2.3.9, MIT, exactly the versions FORD asks for)
into the site, points every page at them (relative paths, so the site also works from
file://), drops MathJax (no page of conmech's Fortran API uses mathematics) and fails if
any page still loads something from the network.

    python scripts/ford_offline.py build/docs/fortran
"""
import pathlib
import re
import shutil
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
ASSETS = ROOT / "docs" / "ford_assets"
# the parts of FORD's pages that go to the network, and what replaces them
BOOTSTRAP_CSS = re.compile(r'<link href="https://cdn\.jsdelivr\.net/npm/bootstrap@[^"]*'
                           r'/bootstrap\.min\.css"[^>]*>', re.S)
BOOTSTRAP_JS = re.compile(r'<script src="https://cdn\.jsdelivr\.net/npm/bootstrap@[^"]*'
                          r'/bootstrap\.bundle\.min\.js"[^>]*></script>', re.S)
MATHJAX = re.compile(r'<script type="text/x-mathjax-config">.*?</script>\s*'
                     r'|<script src="https://cdn\.jsdelivr\.net/npm/mathjax@[^"]*"[^>]*>'
                     r'</script>', re.S)
LUNR = re.compile(r'<script src="https://unpkg\.com/lunr/lunr\.js"></script>')
PREFIX = re.compile(r'href="([^"]*)css/fontawesome\.min\.css"')
REMOTE = re.compile(r'(?:src|href)="(https?://[^"]*\.(?:js|css)[^"]*)"')


def main(site):
    site = pathlib.Path(site)
    for name, sub in (("bootstrap.min.css", "css"), ("bootstrap.bundle.min.js", "js"),
                      ("lunr.min.js", "js")):
        (site / sub).mkdir(exist_ok=True)
        shutil.copyfile(ASSETS / name, site / sub / name)
    remote = []
    for page in site.rglob("*.html"):
        text = page.read_text(encoding="utf-8")
        m = PREFIX.search(text)
        pre = m.group(1) if m else ""
        new = BOOTSTRAP_CSS.sub(f'<link href="{pre}css/bootstrap.min.css" rel="stylesheet">',
                                text)
        new = BOOTSTRAP_JS.sub(f'<script src="{pre}js/bootstrap.bundle.min.js"></script>', new)
        new = MATHJAX.sub("", new)
        new = LUNR.sub(f'<script src="{pre}js/lunr.min.js"></script>', new)
        if new != text:
            page.write_text(new, encoding="utf-8")
        remote += [f"{page.relative_to(site)}: {u}" for u in REMOTE.findall(new)]
    if remote:
        print("ford_offline: pages still load from the network:\n  " + "\n  ".join(remote[:10]),
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else ROOT / "build" / "docs" / "fortran"))
