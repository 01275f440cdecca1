#!/usr/bin/env python3
"""Checks that a report.html leads the eye, in headless Chromium at 1400 px wide.

For each report given, or for the 8x8 thesis-size set it makes itself (`era simulate
modal --collocated --noise 0.05`, then `era identify --states auto --out`):

- the file is at most 3 MB;
- the table of contents, the summary and the mode table start within the first 3000 px,
  and the stabilization diagram (when the run scanned orders) ends within them;
- every link of the table of contents names an element of the page;
- the page logs no console error and requests nothing but itself.

It saves a 1400 x 3000 screenshot of each report's top (layout_N.png) to look at, and
with --shoot the elements of those ids (ID_N.png).
Standard library only; the DevTools client is check_viewer.py's.

Usage: scripts/check_report_layout.py [--era target/release/era] [--out DIR] [--shoot ID,...] [REPORT ...]
Exit status 0 when every check passes, 1 when one fails, 2 when Chromium or era is
missing (said loudly: this is not a skip).
"""

import argparse
import base64
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_viewer import (chromium_page, console_errors, find_chromium, report_failures,  # noqa: E402
                          requests_besides)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
WIDTH, HEIGHT = 1400, 3000
MAX_BYTES = 3 * 1024 * 1024

GEOMETRY = """(() => {
  const box = id => { const e = document.getElementById(id); if (!e) return null;
    const r = e.getBoundingClientRect(); return [r.top + window.scrollY, r.bottom + window.scrollY]; };
  const links = [...document.querySelectorAll('#toc a')].map(a => a.getAttribute('href'));
  return { toc: box('toc'), summary: box('summary'), modes: box('modal-table'),
           stabilization: box('fig-stabilization'), links: links,
           missing: links.filter(h => !h.startsWith('#') || !document.getElementById(h.slice(1))) };
})()"""


def thesis_size_report(era, out):
    frf = os.path.join(out, "dta.csv")
    subprocess.run([era, "simulate", "modal", "--collocated", "--noise", "0.05", "--seed", "1",
                    "--out", frf, "-q"], check=True)
    run = os.path.join(out, "dta-auto")
    subprocess.run([era, "identify", frf, "--states", "auto", "--out", run, "-q"], check=True)
    return os.path.join(run, "report.html")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--era", default=os.path.join(ROOT, "target", "release", "era"))
    ap.add_argument("--out", default=None, help="folder for the run and the screenshots (default: a temporary one, kept)")
    ap.add_argument("--chromium", default=None)
    ap.add_argument("--shoot", default="", help="comma list of element ids to save as pictures too (ID_N.png)")
    ap.add_argument("reports", nargs="*")
    a = ap.parse_args()
    browser = find_chromium(a.chromium)
    if not browser:
        print("check_report_layout: FAILED: no chromium on PATH (apt-get install chromium)", file=sys.stderr)
        return 2
    out = a.out or tempfile.mkdtemp(prefix="check-layout-")
    os.makedirs(out, exist_ok=True)
    reports = a.reports
    if not reports:
        if not os.path.isfile(a.era):
            print(f"check_report_layout: FAILED: no era binary at {a.era}", file=sys.stderr)
            return 2
        reports = [thesis_size_report(a.era, out)]

    failures = []

    def check(ok, what):
        print(("  ok    " if ok else "  FAIL  ") + what)
        if not ok:
            failures.append(what)

    with chromium_page(browser, WIDTH, HEIGHT) as cdp:
        cdp.call("Emulation.setDeviceMetricsOverride", width=WIDTH, height=HEIGHT, deviceScaleFactor=1, mobile=False)
        for n, page in enumerate(reports, start=1):
            size = os.path.getsize(page)
            print(f"check_report_layout: {page} ({size} bytes)")
            check(size <= MAX_BYTES, f"at most 3 MB ({size / 1048576:.2f} MB)")
            cdp.events = []
            url = "file://" + os.path.abspath(page)
            cdp.call("Page.navigate", url=url)
            cdp.wait_event("Page.loadEventFired")
            cdp.js("new Promise(r => setTimeout(r, 300))")
            g = cdp.js(GEOMETRY)
            for key, name in [("toc", "the table of contents"), ("summary", "the summary"), ("modes", "the mode table")]:
                box = g[key]
                check(box is not None and box[0] < HEIGHT,
                      f"{name} starts within the first {HEIGHT} px ({'absent' if box is None else f'at {box[0]:.0f} px'})")
            if g["stabilization"] is not None:
                check(g["stabilization"][1] <= HEIGHT,
                      f"the stabilization diagram ends within the first {HEIGHT} px (at {g['stabilization'][1]:.0f} px)")
            else:
                print("  --    no stabilization diagram in this report (a fixed order)")
            check(len(g["links"]) >= 4 and not g["missing"],
                  f"the table of contents' {len(g['links'])} links all resolve (missing: {g['missing']})")
            data = cdp.call("Page.captureScreenshot", format="png",
                            clip={"x": 0, "y": 0, "width": WIDTH, "height": HEIGHT, "scale": 1})["data"]
            shot = os.path.join(out, f"layout_{n}.png")
            with open(shot, "wb") as f:
                f.write(base64.b64decode(data))
            print(f"  saved {shot}")
            for ident in filter(None, a.shoot.split(",")):
                box = cdp.js(f"""(() => {{ const e = document.getElementById({json.dumps(ident)}); if (!e) return null;
                    e.scrollIntoView(); const r = e.getBoundingClientRect();
                    return [r.left + window.scrollX, r.top + window.scrollY, r.width, r.height]; }})()""")
                if box is None:
                    print(f"  --    no element {ident}")
                    continue
                cdp.js("new Promise(r => setTimeout(r, 200))")
                data = cdp.call("Page.captureScreenshot", format="png", captureBeyondViewport=True,
                                clip={"x": box[0], "y": box[1], "width": box[2], "height": box[3], "scale": 1})["data"]
                path = os.path.join(out, f"{ident}_{n}.png")
                with open(path, "wb") as f:
                    f.write(base64.b64decode(data))
                print(f"  saved {path}")
            errors = console_errors(cdp, ("error", "assert"))
            check(not errors, f"no console errors ({len(errors)}: {json.dumps(errors)[:300]})")
            _, others = requests_besides(cdp, url)
            check(not others, f"no network requests besides the page (others: {others[:5]})")
    return report_failures(failures, "check_report_layout")


if __name__ == "__main__":
    sys.exit(main())
