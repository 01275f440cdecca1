#!/usr/bin/env python3
"""Checks the mode-shape viewer of report.html in headless Chromium.

Builds an FRF set whose modes are known shapes on the ARTeMIS geometry shipped in
data/pyuff-artemis-geometry (vertical bending, sway, torsion, second bending; outputs
in +Z and +Y at every node and one channel on a node the geometry does not have), runs
`era identify --geometry` on it, opens report.html in headless Chromium through the
DevTools protocol and checks that:

- the canvas changes between two captures 0.5 s apart (the animation runs);
- it stops changing when paused;
- picking another mode (from the list, or by clicking a row of the mode table)
  changes the picture and the caption;
- the page logs no console error and throws no exception;
- the page requests nothing but itself (no network);
- with prefers-reduced-motion it starts paused;
- the three-views button changes the picture.

With --report on a report made without a geometry it checks instead that the report
says so, carries no viewer and has its mode table.

It saves screenshots of the viewer (viewer_mode1.png, viewer_mode3.png,
viewer_three.png) in the output folder to look at. Standard library only (a minimal WebSocket client is below).

Usage: scripts/check_viewer.py [--era target/release/era] [--out DIR] [--chromium PATH]
Exit status 0 when every check passes, 1 when one fails, 2 when Chromium or era is
missing (said loudly: this is not a skip).
"""

import argparse
import base64
import contextlib
import json
import math
import os
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.parse
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GEOMETRY = os.path.join(ROOT, "data", "pyuff-artemis-geometry", "artemis_geometry_rpbc.uff")


def read_nodes(path):
    """Dataset 15 of a UFF file: {node id: (x, y, z)}."""
    nodes = {}
    lines = open(path).read().splitlines()
    k = 0
    while k < len(lines):
        if lines[k].strip() == "-1" and k + 1 < len(lines) and lines[k + 1].strip() == "15":
            k += 2
            while lines[k].strip() != "-1":
                f = lines[k].split()
                nodes[int(f[0])] = tuple(float(v) for v in f[4:7])
                k += 1
        k += 1
    return nodes


def write_frf(path, nodes):
    """An acceleration FRF set (one input) whose four modes are shapes defined on the
    node coordinates; returns the number of outputs."""
    xs, ys, zs = zip(*nodes.values())
    span = lambda v: (min(v), max(v) - min(v) or 1.0)
    (x0, dx), (y0, dy), (z0, dz) = span(xs), span(ys), span(zs)
    ids = sorted(nodes)
    channels = []  # (node, direction, [shape entry of each mode])
    for n in ids:
        x, y, z = nodes[n]
        xi, eta, zeta = (x - x0) / dx, (y - y0) / dy, (z - z0) / dz
        bend = math.sin(math.pi * xi)
        channels.append((n, "+Z", [bend, 0.2 * bend, (eta - 0.5) * 2 * bend, math.sin(2 * math.pi * xi)]))
        channels.append((n, "+Y", [0.05 * bend, (0.3 + zeta) * bend, -(zeta - 0.5) * bend, 0.0]))
    channels.append((999, "+Z", [0.5, 0.5, 0.5, 0.5]))  # not in the geometry
    modes = [(2.0, 0.01), (3.1, 0.012), (4.5, 0.008), (6.2, 0.015)]
    df, lines = 0.025, 801
    with open(path, "w") as out:
        out.write("# quantity: acceleration\n# source: scripts/check_viewer.py\n")
        for k, (n, d, _) in enumerate(channels):
            out.write(f"# output_{k + 1}: node {n} {d}\n")
        out.write("# input_1: node 16 +Z\n")
        out.write("frequency_hz," + ",".join(f"H{k + 1}_1_re,H{k + 1}_1_im" for k in range(len(channels))) + "\n")
        for line in range(lines):
            f = line * df
            w = 2 * math.pi * f
            row = [f"{f:.6g}"]
            for _, _, shape in channels:
                h = 0j
                for (fk, zk), phi in zip(modes, shape):
                    wk = 2 * math.pi * fk
                    h += phi * (-w * w) / (wk * wk - w * w + 2j * zk * wk * w)
                row += [repr(h.real), repr(h.imag)]
            out.write(",".join(row) + "\n")
    return len(channels)


class DevTools:
    """A DevTools protocol client over a minimal WebSocket (RFC 6455, client side)."""

    def __init__(self, url):
        u = urllib.parse.urlparse(url)
        self.sock = socket.create_connection((u.hostname, u.port), timeout=60)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall(
            (f"GET {u.path} HTTP/1.1\r\nHost: {u.hostname}:{u.port}\r\nUpgrade: websocket\r\n"
             f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        buf = b""
        while b"\r\n\r\n" not in buf:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise RuntimeError("DevTools closed the connection during the handshake")
            buf += chunk
        head, self.buf = buf.split(b"\r\n\r\n", 1)
        if b" 101 " not in head.split(b"\r\n")[0]:
            raise RuntimeError(f"WebSocket handshake refused: {head[:200]!r}")
        self.next_id = 0
        self.events = []

    def _read(self, n):
        while len(self.buf) < n:
            chunk = self.sock.recv(1 << 16)
            if not chunk:
                raise RuntimeError("DevTools closed the connection")
            self.buf += chunk
        out, self.buf = self.buf[:n], self.buf[n:]
        return out

    def _message(self):
        data = b""
        while True:
            b0, b1 = self._read(2)
            n = b1 & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._read(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._read(8))[0]
            mask = self._read(4) if b1 & 0x80 else None
            payload = self._read(n)
            if mask:
                payload = bytes(c ^ mask[i % 4] for i, c in enumerate(payload))
            opcode = b0 & 0x0F
            if opcode == 8:
                raise RuntimeError("DevTools closed the WebSocket")
            if opcode in (0, 1, 2):
                data += payload
                if b0 & 0x80:
                    return json.loads(data)

    def call(self, method, **params):
        self.next_id += 1
        text = json.dumps({"id": self.next_id, "method": method, "params": params}).encode()
        head = bytes([0x81])
        if len(text) < 126:
            head += bytes([0x80 | len(text)])
        elif len(text) < 1 << 16:
            head += bytes([0x80 | 126]) + struct.pack(">H", len(text))
        else:
            head += bytes([0x80 | 127]) + struct.pack(">Q", len(text))
        mask = os.urandom(4)
        self.sock.sendall(head + mask + bytes(c ^ mask[i % 4] for i, c in enumerate(text)))
        while True:
            m = self._message()
            if m.get("id") == self.next_id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            self.events.append(m)

    def wait_event(self, method, timeout=60):
        end = time.time() + timeout
        while time.time() < end:
            for e in self.events:
                if e.get("method") == method:
                    return e
            self.events.append(self._message())
        raise RuntimeError(f"no {method} within {timeout} s")

    def js(self, expression):
        r = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expression}: {r['exceptionDetails']}")
        return r["result"].get("value")


def find_chromium(given):
    for name in [given] if given else ["chromium", "chromium-browser", "google-chrome"]:
        path = shutil.which(name) if name else None
        if path:
            return path
    return None


@contextlib.contextmanager
def chromium_page(browser, width, height, domains=("Page", "Runtime", "Log", "Network")):
    """A headless Chromium with one page at `width` x `height`, its DevTools client
    (`domains` enabled); the browser and its profile are gone afterwards."""
    profile = tempfile.mkdtemp(prefix="era-chromium-profile-")
    proc = subprocess.Popen(
        [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--disable-dev-shm-usage", "--no-first-run",
         "--hide-scrollbars", "--remote-debugging-port=0", f"--window-size={width},{height}",
         f"--user-data-dir={profile}", "about:blank"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        port_file = os.path.join(profile, "DevToolsActivePort")
        for _ in range(600):
            if os.path.exists(port_file) and open(port_file).read().strip():
                break
            time.sleep(0.1)
        port = int(open(port_file).read().split()[0])
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list"))
        cdp = DevTools(next(t for t in targets if t.get("type") == "page")["webSocketDebuggerUrl"])
        for domain in domains:
            cdp.call(f"{domain}.enable")
        yield cdp
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
        shutil.rmtree(profile, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--era", default=os.path.join(ROOT, "target", "release", "era"))
    ap.add_argument("--out", default=None, help="folder for the run and the screenshots (default: a temporary one, kept)")
    ap.add_argument("--chromium", default=None)
    ap.add_argument("--report", default=None,
                    help="check this report.html (made with --geometry, two modes or more) instead of the ARTeMIS run")
    a = ap.parse_args()
    browser = find_chromium(a.chromium)
    if not browser:
        print("check_viewer: FAILED: no chromium on PATH (apt-get install chromium); the viewer was not checked", file=sys.stderr)
        return 2
    if not os.path.isfile(a.era):
        print(f"check_viewer: FAILED: no era binary at {a.era} (cargo build --release -p era-cli --bin era)", file=sys.stderr)
        return 2
    out = a.out or tempfile.mkdtemp(prefix="check-viewer-")
    os.makedirs(out, exist_ok=True)
    if a.report:
        page = a.report
    else:
        frf = os.path.join(out, "artemis_frf.csv")
        q = write_frf(frf, read_nodes(GEOMETRY))
        run = os.path.join(out, "run")
        subprocess.run([a.era, "identify", frf, "--states", "8", "--geometry", GEOMETRY, "--out", run, "-q"], check=True)
        page = os.path.join(run, "report.html")
        print(f"check_viewer: {q} outputs on the ARTeMIS geometry")
    print(f"check_viewer: report {os.path.getsize(page)} bytes: {page}")

    failures = []

    def check(ok, what):
        print(("  ok    " if ok else "  FAIL  ") + what)
        if not ok:
            failures.append(what)

    with chromium_page(browser, 1200, 1000) as cdp:
        url = "file://" + os.path.abspath(page)
        cdp.call("Page.navigate", url=url)
        cdp.wait_event("Page.loadEventFired")
        cdp.js("new Promise(r => setTimeout(r, 300))")

        canvas = "document.getElementById('shape-canvas').toDataURL()"
        if a.report and not cdp.js("!!document.getElementById('shape-canvas')"):
            # A report without a geometry: one line says so, and no viewer runs.
            none = cdp.js("(document.getElementById('shapes-none') || {}).textContent || ''")
            check("geometry" in none, f"without a geometry the report says so ({none[:80]!r})")
            check(not cdp.js("!!document.getElementById('era-shapes')"), "and carries no viewer data")
            check(cdp.js("document.querySelectorAll('#modal-table tr').length") >= 2, "the mode table is there")
            errors = [e for e in cdp.events if e.get("method") == "Runtime.exceptionThrown"]
            check(not errors, f"no exceptions ({len(errors)})")
            return report_failures(failures)
        check(cdp.js("!!document.getElementById('shape-canvas')"), "the report has the viewer's canvas")
        listed = cdp.js("document.querySelectorAll('#shape-mode option').length")
        table = cdp.js("document.querySelectorAll('#modal-table tr').length - 1")
        if a.report:
            check(listed == table and listed >= 2, f"one entry per mode of the table in the list ({listed} of {table})")
        else:
            check(listed == 4, f"the four modes in the list ({listed})")
        first = cdp.js(canvas)
        cdp.js("new Promise(r => setTimeout(r, 500))")
        second = cdp.js(canvas)
        check(first != second, "the canvas changes between two captures 0.5 s apart")
        inked = cdp.js("""(() => { const c = document.getElementById('shape-canvas');
            const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data; let n = 0;
            for (let i = 0; i < d.length; i += 4) if (d[i] < 200 || d[i + 1] < 200) n++;
            return n / (c.width * c.height); })()""")
        check(inked > 0.002, f"the canvas is drawn ({100 * inked:.2f} % of its pixels inked)")

        # The viewer and the list of channels not drawn below it.
        viewer_box = cdp.js("""(() => { const r = document.getElementById('shape-viewer').getBoundingClientRect();
            const b = document.getElementById('shapes-not-drawn').getBoundingClientRect();
            return [r.left + window.scrollX, r.top + window.scrollY, r.width, b.bottom - r.top + 8]; })()""")

        def shot(name):
            x, y, w, h = viewer_box
            data = cdp.call("Page.captureScreenshot", format="png", captureBeyondViewport=True,
                            clip={"x": x, "y": y, "width": w, "height": h, "scale": 1})["data"]
            with open(os.path.join(out, name), "wb") as f:
                f.write(base64.b64decode(data))

        cdp.js("document.getElementById('shape-play').click()")
        paused = cdp.js(canvas)
        cdp.js("new Promise(r => setTimeout(r, 500))")
        check(cdp.js(canvas) == paused, "paused, the canvas stays still")
        check(cdp.js("document.getElementById('shape-play').textContent") == "Play", "the button then reads Play")
        # The stills at the largest deflection (phase 0).
        cdp.js("document.getElementById('shape-canvas').eraShowPhase(0)")
        shot("viewer_mode1.png")
        still = cdp.js(canvas)

        cdp.js("(() => { const s = document.getElementById('shape-mode'); s.value = '1'; s.dispatchEvent(new Event('change')); })()")
        other = cdp.js(canvas)
        check(other != still, "picking mode 2 from the list changes the picture")
        check(cdp.js("document.getElementById('shape-caption').textContent").startswith("Mode 2:"), "the caption names mode 2")

        cdp.js("document.querySelectorAll('#modal-table tr')[3].click()")
        check(cdp.js("document.getElementById('shape-mode').value") == "2", "clicking the third row of the mode table picks mode 3")
        check(cdp.js(canvas) != other, "and changes the picture")
        shot("viewer_mode3.png")

        before = cdp.js(canvas)
        cdp.js("(() => { const a = document.getElementById('shape-amplitude'); a.value = '30'; a.dispatchEvent(new Event('input')); })()")
        check(cdp.js(canvas) != before, "a larger amplitude changes the picture")
        check(cdp.js("document.getElementById('shape-amplitude-value').textContent") == "30 %", "the amplitude reads 30 %")
        # The three views side by side, as the static pictures show them.
        before = cdp.js(canvas)
        cdp.js("document.querySelector('[data-shape-view=three]').click()")
        cdp.js("document.getElementById('shape-canvas').eraShowPhase(0)")
        check(cdp.js(canvas) != before, "the three-views button changes the picture")
        shot("viewer_three.png")
        cdp.js("document.querySelector('[data-shape-view=iso]').click()")
        if not a.report:
            not_drawn = cdp.js("document.getElementById('shapes-not-drawn').textContent")
            check("node 999 is not in the geometry" in not_drawn, "the channel on node 999 is listed as not drawn")

        # A reader who asks for reduced motion gets a still, and Play.
        cdp.call("Emulation.setEmulatedMedia", features=[{"name": "prefers-reduced-motion", "value": "reduce"}])
        cdp.events = [e for e in cdp.events if e.get("method") != "Page.loadEventFired"]
        cdp.call("Page.reload")
        cdp.wait_event("Page.loadEventFired")
        first = cdp.js(canvas)
        cdp.js("new Promise(r => setTimeout(r, 500))")
        check(cdp.js(canvas) == first and cdp.js("document.getElementById('shape-play').textContent") == "Play",
              "with prefers-reduced-motion the viewer starts paused")

        # Let any late error surface, then read the events.
        cdp.js("new Promise(r => setTimeout(r, 300))")
        errors = console_errors(cdp, ("error", "assert", "warning"))
        check(not errors, f"no console errors or exceptions ({len(errors)}: {json.dumps(errors)[:500]})")
        requests, others = requests_besides(cdp, url)
        check(not others, f"no network requests besides the page ({len(requests)} request(s); others: {others[:5]})")
    print(f"check_viewer: screenshots in {out}")
    return report_failures(failures)


def console_errors(cdp, levels):
    """The page's exceptions, and its console calls and log entries at one of `levels`
    ("error", "assert", "warning"), from the events a chromium_page session recorded."""
    return [e for e in cdp.events if e.get("method") == "Runtime.exceptionThrown"
            or (e.get("method") == "Runtime.consoleAPICalled" and e["params"]["type"] in levels)
            or (e.get("method") == "Log.entryAdded" and e["params"]["entry"]["level"] in levels)]


def requests_besides(cdp, url):
    """Every URL the page requested, and those other than `url` itself."""
    requests = [e["params"]["request"]["url"] for e in cdp.events if e.get("method") == "Network.requestWillBeSent"]
    return requests, [r for r in requests if r != url]


def report_failures(failures, name="check_viewer"):
    """The closing line of a check script named `name`, and its exit code."""
    if failures:
        print(f"{name}: FAILED {len(failures)} check(s)", file=sys.stderr)
        return 1
    print(f"{name}: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
