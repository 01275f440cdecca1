// era's mode-shape viewer: the modes of report.html animated on the test geometry.
// Plain canvas 2-D drawing with an orthographic camera; no library, no network.
// The data is the JSON in <script id="era-shapes"> (crates/era-plot/src/viewer.rs).
(function () {
  "use strict";
  var source = document.getElementById("era-shapes");
  var canvas = document.getElementById("shape-canvas");
  if (!source || !canvas || !canvas.getContext) {
    return;
  }
  var data = JSON.parse(source.textContent);
  var ctx = canvas.getContext("2d");
  var pick = document.getElementById("shape-mode");
  var playButton = document.getElementById("shape-play");
  var amplitude = document.getElementById("shape-amplitude");
  var amplitudeText = document.getElementById("shape-amplitude-value");
  var caption = document.getElementById("shape-caption");
  var nodes = data.nodes;
  var segments = data.segments;
  var PERIOD_S = 1.6; // one cycle of the animation, whatever the mode's frequency

  // The undeformed structure's centre and size: the camera turns about the centre and
  // keeps one scale, so that rotating never zooms.
  var lo = [Infinity, Infinity, Infinity];
  var hi = [-Infinity, -Infinity, -Infinity];
  nodes.forEach(function (p) {
    for (var a = 0; a < 3; a++) {
      lo[a] = Math.min(lo[a], p[a]);
      hi[a] = Math.max(hi[a], p[a]);
    }
  });
  var centre = [0, 1, 2].map(function (a) { return 0.5 * (lo[a] + hi[a]); });
  var size = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 1;

  var state = {
    mode: 0,
    playing: true,
    phase: 0,
    yaw: -0.6,
    pitch: 0.45,
    started: null,
    phaseAtStart: 0,
    zoom: 0.8,
    shift: [0, 0],
    three: false
  };

  // The three orthographic views drawn side by side (the static pictures' layout).
  var THREE_VIEWS = [
    { name: "front (x\u2013z)", yaw: 0, pitch: 0 },
    { name: "side (y\u2013z)", yaw: -Math.PI / 2, pitch: 0 },
    { name: "top (x\u2013y)", yaw: 0, pitch: Math.PI / 2 }
  ];

  // The zoom that fills the canvas with the undeformed structure seen from the current
  // view, leaving room for the deflection; kept while dragging, so rotating never zooms.
  function fit() {
    fitTo(canvas.clientWidth || 800, canvas.clientHeight || 480);
  }

  // The same for a picture of width x height pixels.
  function fitTo(width, height) {
    state.zoom = 1;
    state.shift = [0, 0];
    var project = projector(width, height);
    var x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
    nodes.forEach(function (p) {
      var q = project(p);
      x0 = Math.min(x0, q[0]); x1 = Math.max(x1, q[0]);
      y0 = Math.min(y0, q[1]); y1 = Math.max(y1, q[1]);
    });
    var zx = (x1 - x0) > 0 ? 0.75 * width / (x1 - x0) : Infinity;
    var zy = (y1 - y0) > 0 ? 0.6 * height / (y1 - y0) : Infinity;
    var z = Math.min(zx, zy);
    state.zoom = isFinite(z) ? z : 0.8;
    // Centre the picture: the middle of the projected extents at the canvas's centre.
    var k1 = Math.min(width, height) / size;
    state.shift = [-(0.5 * (x0 + x1) - width / 2) / k1, (0.5 * (y0 + y1) - height / 2) / k1];
  }

  // Displacement of every node at `phase`: Re(u e^{i phase}), zero where no channel is.
  function displaced(phase) {
    var mode = data.modes[state.mode];
    var scale = (amplitude ? Number(amplitude.value) : 10) / 100 * size;
    var c = Math.cos(phase);
    var s = Math.sin(phase);
    var out = nodes.map(function (p) { return [p[0], p[1], p[2]]; });
    mode.u.forEach(function (row) {
      var p = out[row[0]];
      for (var a = 0; a < 3; a++) {
        var re = row[1 + 2 * a];
        var im = row[2 + 2 * a];
        p[a] += scale * (re * c - im * s);
      }
    });
    return out;
  }

  // Orthographic projection: turn about the vertical (z) axis by yaw, then tilt by
  // pitch (looking down for pitch > 0). Returns canvas pixels.
  function projector(width, height) {
    var cy = Math.cos(state.yaw);
    var sy = Math.sin(state.yaw);
    var cp = Math.cos(state.pitch);
    var sp = Math.sin(state.pitch);
    var k = state.zoom * Math.min(width, height) / size;
    return function (p) {
      var x = p[0] - centre[0];
      var y = p[1] - centre[1];
      var z = p[2] - centre[2];
      var xr = x * cy - y * sy;
      var yr = x * sy + y * cy;
      var up = z * cp + yr * sp;
      return [width / 2 + k * (xr + state.shift[0]), height / 2 - k * (up + state.shift[1])];
    };
  }

  function strokeSegments(points, colour, width, dash) {
    ctx.strokeStyle = colour;
    ctx.lineWidth = width;
    ctx.setLineDash(dash);
    ctx.beginPath();
    segments.forEach(function (s) {
      var a = points[s[0]];
      var b = points[s[1]];
      ctx.moveTo(a[0], a[1]);
      ctx.lineTo(b[0], b[1]);
    });
    ctx.stroke();
    ctx.setLineDash([]);
  }

  function dots(points, fill, radius, which) {
    ctx.fillStyle = fill;
    ctx.strokeStyle = fill;
    ctx.lineWidth = 1;
    which.forEach(function (k) {
      var p = points[k];
      ctx.beginPath();
      ctx.arc(p[0], p[1], radius, 0, 2 * Math.PI);
      if (data.measured[k]) {
        ctx.fill();
      } else {
        ctx.stroke();
      }
    });
  }

  // The global axes in the lower left corner, turned with the structure.
  function triad(width, height) {
    var project = projector(width, height);
    var o = project(centre);
    var names = ["x", "y", "z"];
    var colours = ["#c0392b", "#27ae60", "#2c6fbb"];
    for (var a = 0; a < 3; a++) {
      var q = centre.slice();
      q[a] += 1;
      var p = project(q);
      var dx = p[0] - o[0];
      var dy = p[1] - o[1];
      var n = Math.hypot(dx, dy);
      var len = 28 * Math.min(1, n / (0.8 * Math.min(width, height) / size));
      var ux = n > 0 ? dx / n : 0;
      var uy = n > 0 ? dy / n : 0;
      var bx = 40;
      var by = height - 40;
      ctx.strokeStyle = colours[a];
      ctx.fillStyle = colours[a];
      ctx.lineWidth = 2;
      ctx.beginPath();
      ctx.moveTo(bx, by);
      ctx.lineTo(bx + len * ux, by + len * uy);
      ctx.stroke();
      ctx.font = "12px sans-serif";
      ctx.fillText(names[a], bx + (len + 7) * ux - 3, by + (len + 7) * uy + 4);
    }
  }

  function draw() {
    var ratio = window.devicePixelRatio || 1;
    var width = canvas.clientWidth || 800;
    var height = canvas.clientHeight || 480;
    if (canvas.width !== Math.round(width * ratio) || canvas.height !== Math.round(height * ratio)) {
      canvas.width = Math.round(width * ratio);
      canvas.height = Math.round(height * ratio);
    }
    ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(0, 0, width, height);
    if (!state.three) {
      scene(width, height);
      triad(width, height);
      return;
    }
    // Three panels, each fitted to its own view; the 3-D camera is kept for later.
    var kept = [state.yaw, state.pitch, state.zoom, state.shift];
    var w = width / 3;
    THREE_VIEWS.forEach(function (v, i) {
      state.yaw = v.yaw;
      state.pitch = v.pitch;
      fitTo(w, height);
      ctx.save();
      ctx.translate(i * w, 0);
      ctx.beginPath();
      ctx.rect(0, 0, w, height);
      ctx.clip();
      scene(w, height);
      ctx.fillStyle = "#333333";
      ctx.font = "13px sans-serif";
      ctx.fillText(v.name, 8, 18);
      if (i > 0) {
        ctx.strokeStyle = "#dddddd";
        ctx.lineWidth = 1;
        ctx.beginPath();
        ctx.moveTo(0.5, 0);
        ctx.lineTo(0.5, height);
        ctx.stroke();
      }
      ctx.restore();
    });
    state.yaw = kept[0];
    state.pitch = kept[1];
    state.zoom = kept[2];
    state.shift = kept[3];
  }

  // The structure, undeformed under deformed, in a picture of width x height pixels.
  function scene(width, height) {
    var project = projector(width, height);
    var rest = nodes.map(project);
    var moved = displaced(state.phase).map(project);
    var all = nodes.map(function (_, k) { return k; });
    var still = all.filter(function (k) { return !data.measured[k]; });
    var measured = all.filter(function (k) { return data.measured[k]; });
    strokeSegments(rest, "#b8b8b8", 1, [4, 3]);
    dots(rest, "#b8b8b8", 1.5, measured);
    strokeSegments(moved, "#1f4e9c", 2, []);
    dots(moved, "#9a9a9a", 2.5, still);
    dots(moved, "#1f4e9c", 2.5, measured);
  }

  // One animation loop at a time: a loop whose token is stale stops.
  var loop = 0;

  function frame(token, time) {
    if (!state.playing || token !== loop) {
      return;
    }
    if (state.started === null) {
      state.started = time;
      state.phaseAtStart = state.phase;
    }
    var t = (time - state.started) / 1000;
    state.phase = (state.phaseAtStart + 2 * Math.PI * t / PERIOD_S) % (2 * Math.PI);
    draw();
    window.requestAnimationFrame(function (t) { frame(token, t); });
  }

  function setPlaying(on) {
    state.playing = on;
    if (playButton) {
      playButton.textContent = on ? "Pause" : "Play";
      playButton.setAttribute("aria-pressed", on ? "true" : "false");
    }
    if (on) {
      state.started = null;
      loop += 1;
      var token = loop;
      window.requestAnimationFrame(function (t) { frame(token, t); });
    } else {
      draw();
    }
  }

  var rows = Array.prototype.slice.call(document.querySelectorAll("#modal-table tr")).slice(1);

  function setMode(k) {
    if (k < 0 || k >= data.modes.length) {
      return;
    }
    state.mode = k;
    if (pick) {
      pick.value = String(k);
    }
    if (caption) {
      caption.textContent = data.modes[k].label;
    }
    rows.forEach(function (row, j) {
      row.classList.toggle("shape-picked", j === k);
    });
    if (!state.playing) {
      draw();
    }
  }

  if (pick) {
    pick.addEventListener("change", function () { setMode(Number(pick.value)); });
  }
  if (playButton) {
    playButton.addEventListener("click", function () { setPlaying(!state.playing); });
  }
  if (amplitude) {
    var showAmplitude = function () {
      if (amplitudeText) {
        amplitudeText.textContent = amplitude.value + " %";
      }
      if (!state.playing) {
        draw();
      }
    };
    amplitude.addEventListener("input", showAmplitude);
    showAmplitude();
  }
  var views = {
    iso: [-0.6, 0.45],
    front: [0, 0],
    side: [-Math.PI / 2, 0],
    top: [0, Math.PI / 2]
  };
  Array.prototype.forEach.call(document.querySelectorAll("[data-shape-view]"), function (b) {
    b.addEventListener("click", function () {
      var name = b.getAttribute("data-shape-view");
      state.three = name === "three";
      if (state.three) {
        if (!state.playing) {
          draw();
        }
        return;
      }
      var v = views[name];
      state.yaw = v[0];
      state.pitch = v[1];
      fit();
      if (!state.playing) {
        draw();
      }
    });
  });
  rows.forEach(function (row, k) {
    if (k < data.modes.length) {
      row.classList.add("shape-pickable");
      row.title = "Show this mode on the geometry";
      row.addEventListener("click", function () {
        setMode(k);
        canvas.scrollIntoView({ block: "nearest" });
      });
    }
  });

  // Drag to rotate: horizontal motion turns about the vertical axis, vertical motion
  // tilts (clamped at straight down and straight up).
  var drag = null;
  canvas.addEventListener("pointerdown", function (e) {
    if (state.three) {
      return;
    }
    drag = { x: e.clientX, y: e.clientY, yaw: state.yaw, pitch: state.pitch };
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener("pointermove", function (e) {
    if (!drag) {
      return;
    }
    state.yaw = drag.yaw + 0.01 * (e.clientX - drag.x);
    var pitch = drag.pitch + 0.01 * (e.clientY - drag.y);
    state.pitch = Math.max(-Math.PI / 2, Math.min(Math.PI / 2, pitch));
    if (!state.playing) {
      draw();
    }
  });
  var endDrag = function () { drag = null; };
  canvas.addEventListener("pointerup", endDrag);
  canvas.addEventListener("pointercancel", endDrag);
  window.addEventListener("resize", function () {
    if (!state.playing) {
      draw();
    }
  });

  // For tests and for a still at a chosen instant: pause, then set the phase (radians;
  // 0 is the largest deflection of the mode's largest component).
  canvas.eraShowPhase = function (phase) {
    setPlaying(false);
    state.phase = Number(phase) || 0;
    draw();
  };

  // A reader who asked for less motion gets the still at the largest deflection; Play
  // starts the cycle.
  var reduceMotion = window.matchMedia && window.matchMedia("(prefers-reduced-motion: reduce)").matches;
  fit();
  setMode(0);
  setPlaying(!reduceMotion);
})();
