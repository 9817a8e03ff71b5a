// glint view: the transfer-function editor over the volume's histogram, and window /
// level by right- or shift-drag on the image (issue 43 item 3). Loaded after app.js,
// whose socket (ws) and update() it shares; window.glintTf exposes its state for the
// browser test.
//
// The editor shows the transfer function the last full frame used (the scene's
// derived.transfer_function: the preset's, windowed), opacity as points over the
// histogram (x the value in the volume's units, y the opacity) and colour as stops on
// the strip below. A click adds a point (a stop on the strip), a drag moves it, a
// double click or a right click deletes it; every edit sends the whole function as
// the scene's transfer_function (which replaces the preset and its window). The
// scene message's window_level (the function's own window) starts the drag.
"use strict";
(() => {
  const $ = (id) => document.getElementById(id);
  const box = $("tf");
  const g = box.getContext("2d");
  const image = $("frame");
  const STRIP = 16; // height of the colour strip, px
  const TOP = 6; // opacity 1 is drawn this far below the top, px
  const HIT = 6; // how near a point a pointer must be to grab it, px
  const s = { histogram: null, tf: null, wl: null, selected: null, drag: null, wlDrag: null };
  const api = (window.glintTf = { state: s, edits: 0, sent: [] });

  // Value axis: the histogram's range (the volume's), else the function's points.
  function axis() {
    if (s.histogram) return s.histogram.range;
    const xs = s.tf ? [...s.tf.opacity, ...s.tf.color].map((p) => p[0]) : [0, 1];
    const lo = Math.min(...xs), hi = Math.max(...xs);
    return hi > lo ? [lo, hi] : [lo, lo + 1];
  }
  const bottom = () => box.height - STRIP - 4;
  const px = (v) => { const [lo, hi] = axis(); return ((v - lo) / (hi - lo)) * box.width; };
  const value = (x) => { const [lo, hi] = axis(); return lo + (x / box.width) * (hi - lo); };
  const py = (a) => TOP + (1 - a) * (bottom() - TOP);
  const opacity = (y) => Math.max(0, Math.min(1, 1 - (y - TOP) / (bottom() - TOP)));

  // Piecewise linear, constant beyond the ends (the server's rule).
  function at(points, v) {
    if (v <= points[0][0]) return points[0].slice(1);
    for (let i = 1; i < points.length; i++) {
      const [x0, ...y0] = points[i - 1], [x1, ...y1] = points[i];
      if (v <= x1) return y0.map((y, c) => y + ((v - x0) / (x1 - x0)) * (y1[c] - y));
    }
    return points[points.length - 1].slice(1);
  }
  const css = (rgb) => `rgb(${rgb.map((c) => Math.round(c * 255)).join(",")})`;

  function draw() {
    const w = box.width, h = box.height;
    g.fillStyle = "#1a1a1a";
    g.fillRect(0, 0, w, h);
    if (s.histogram) {
      const bins = s.histogram.log_counts, top = Math.max(...bins, 1e-6);
      g.fillStyle = "#444";
      bins.forEach((c, i) => {
        const bh = (c / top) * (bottom() - TOP);
        g.fillRect((i / bins.length) * w, bottom() - bh, w / bins.length + 0.5, bh);
      });
    }
    if (!s.tf) return;
    for (let x = 0; x < w; x++) {
      g.fillStyle = css(at(s.tf.color, value(x + 0.5)));
      g.fillRect(x, h - STRIP, 1, STRIP);
    }
    g.strokeStyle = "#eee";
    g.beginPath();
    g.moveTo(0, py(at(s.tf.opacity, value(0))[0]));
    for (const [x, a] of s.tf.opacity) g.lineTo(px(x), py(a));
    g.lineTo(w, py(at(s.tf.opacity, value(w))[0]));
    g.stroke();
    s.tf.opacity.forEach(([x, a], i) => {
      g.beginPath();
      g.arc(px(x), py(a), 4, 0, 2 * Math.PI);
      g.fillStyle = sel("opacity", i) ? "#fc4" : "#fff";
      g.fill();
    });
    s.tf.color.forEach(([x, ...rgb], i) => {
      g.fillStyle = css(rgb);
      g.strokeStyle = sel("color", i) ? "#fc4" : "#fff";
      g.fillRect(px(x) - 4, h - STRIP - 3, 8, STRIP + 2);
      g.strokeRect(px(x) - 4, h - STRIP - 3, 8, STRIP + 2);
    });
  }
  const sel = (kind, i) => s.selected && s.selected.kind === kind && s.selected.i === i;

  // The point (or stop) under canvas position (x, y): {kind, i} or null.
  function hit(x, y) {
    if (!s.tf) return null;
    if (y >= box.height - STRIP - 4) {
      const i = s.tf.color.findIndex((p) => Math.abs(px(p[0]) - x) <= HIT);
      return i < 0 ? null : { kind: "color", i };
    }
    const i = s.tf.opacity.findIndex(([v, a]) => Math.hypot(px(v) - x, py(a) - y) <= HIT);
    return i < 0 ? null : { kind: "opacity", i };
  }
  function local(e) {
    const r = box.getBoundingClientRect();
    return [((e.clientX - r.left) / r.width) * box.width, ((e.clientY - r.top) / r.height) * box.height];
  }
  function send(interactive) {
    const tf = { opacity: s.tf.opacity.map((p) => p.slice()), color: s.tf.color.map((p) => p.slice()) };
    api.edits += 1;
    api.sent.push(tf);
    update({ transfer_function: tf }, interactive);
  }
  // Inserts a point keeping the values strictly increasing; its index, or -1.
  function insert(points, p) {
    if (points.some((q) => q[0] === p[0])) return -1;
    const i = points.findIndex((q) => q[0] > p[0]);
    const at = i < 0 ? points.length : i;
    points.splice(at, 0, p);
    return at;
  }
  function remove(h) {
    const points = s.tf[h.kind];
    if (points.length <= 1) return; // the function needs one of each
    points.splice(h.i, 1);
    s.selected = null;
    draw();
    send(false);
  }

  box.addEventListener("pointerdown", (e) => {
    if (e.button !== 0 || !s.tf) return;
    const [x, y] = local(e);
    let h = hit(x, y);
    if (!h) {
      const v = value(x);
      if (y >= box.height - STRIP - 4) {
        const i = insert(s.tf.color, [v, ...at(s.tf.color, v)]);
        h = i < 0 ? null : { kind: "color", i };
      } else {
        const i = insert(s.tf.opacity, [v, opacity(y)]);
        h = i < 0 ? null : { kind: "opacity", i };
      }
      if (!h) return;
      s.selected = h;
      draw();
      send(false);
    }
    s.selected = h;
    if (h.kind === "color") $("tf-color").value = "#" + s.tf.color[h.i].slice(1).map((c) => Math.round(c * 255).toString(16).padStart(2, "0")).join("");
    s.drag = { ...h, moved: false };
    box.setPointerCapture(e.pointerId);
    draw();
  });
  box.addEventListener("pointermove", (e) => {
    if (!s.drag) return;
    const [x, y] = local(e);
    const points = s.tf[s.drag.kind], i = s.drag.i;
    const [lo, hi] = axis(), eps = (hi - lo) * 1e-4;
    const left = i > 0 ? points[i - 1][0] + eps : -Infinity;
    const right = i + 1 < points.length ? points[i + 1][0] - eps : Infinity;
    points[i][0] = Math.max(left, Math.min(right, value(x)));
    if (s.drag.kind === "opacity") points[i][1] = opacity(y);
    s.drag.moved = true;
    draw();
    send(true);
  });
  box.addEventListener("pointerup", () => {
    if (s.drag && s.drag.moved) send(false);
    s.drag = null;
  });
  box.addEventListener("dblclick", (e) => { const h = hit(...local(e)); if (h) remove(h); });
  box.addEventListener("contextmenu", (e) => {
    e.preventDefault();
    const h = hit(...local(e));
    if (h) remove(h);
  });
  $("tf-color").addEventListener("input", (e) => {
    if (!s.selected || s.selected.kind !== "color") return;
    const hex = e.target.value;
    const rgb = [1, 3, 5].map((k) => parseInt(hex.slice(k, k + 2), 16) / 255);
    s.tf.color[s.selected.i].splice(1, 3, ...rgb);
    draw();
    send(false);
  });

  // Window / level: a right- or shift-drag on the image; horizontal widens the window
  // (by e per 200 px), vertical moves the level (up: higher; the value range per
  // image height). Captured before app.js's orbit, which it stops.
  function showWl() {
    $("wl").textContent = s.wl ? `W ${s.wl.window.toPrecision(4)} · L ${s.wl.level.toPrecision(4)}` : "";
  }
  image.addEventListener("contextmenu", (e) => e.preventDefault());
  image.addEventListener("pointerdown", (e) => {
    if (!(e.button === 2 || (e.button === 0 && e.shiftKey)) || !s.wl) return;
    e.stopImmediatePropagation();
    image.setPointerCapture(e.pointerId);
    s.wlDrag = { x: e.clientX, y: e.clientY, ...s.wl };
  }, { capture: true });
  image.addEventListener("pointermove", (e) => {
    if (!s.wlDrag) return;
    e.stopImmediatePropagation();
    const [lo, hi] = axis(), d = s.wlDrag;
    const perPixel = (hi - lo) / image.getBoundingClientRect().height;
    s.wl = { window: d.window * Math.exp((e.clientX - d.x) / 200), level: d.level - (e.clientY - d.y) * perPixel };
    showWl();
    update({ window_level: s.wl }, true);
  }, { capture: true });
  image.addEventListener("pointerup", (e) => {
    if (!s.wlDrag) return;
    e.stopImmediatePropagation();
    s.wlDrag = null;
    update({ window_level: s.wl }, false);
  }, { capture: true });

  // The histogram once; each full frame's scene (the latest update's only: an older
  // one would undo edits made since) gives the function and window it used.
  ws.addEventListener("message", (ev) => {
    if (typeof ev.data !== "string") return;
    const msg = JSON.parse(ev.data);
    if (msg.type === "histogram") {
      s.histogram = msg;
      draw();
    } else if (msg.type === "scene" && msg.seq === seq && !s.drag && !s.wlDrag) {
      const d = msg.scene.derived || {};
      s.tf = d.transfer_function ? { opacity: d.transfer_function.opacity, color: d.transfer_function.color } : null;
      s.wl = msg.window_level || null;
      if (s.selected && (!s.tf || !s.tf[s.selected.kind][s.selected.i])) s.selected = null;
      $("tf-box").hidden = !s.tf;
      showWl();
      draw();
      api.scenes = (api.scenes || 0) + 1;
    }
  });

  // Where a point is on the page (for tests and tools): opacity points over the
  // histogram, colour stops on the strip.
  api.screen = (v, a) => {
    const r = box.getBoundingClientRect();
    const y = a === undefined ? box.height - STRIP / 2 : py(a);
    return { x: r.left + (px(v) / box.width) * r.width, y: r.top + (y / box.height) * r.height };
  };
})();
