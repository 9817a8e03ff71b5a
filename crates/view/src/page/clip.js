// glint view: cutting. The "Cut" panel sets a crop box (starting at the volume's
// bounds, one min and max slider per axis) and a clip plane across an axis (an offset
// slider; "flip" swaps the side kept); a slider's drag sends interactive scene
// patches ({crop}, {clip}), as an orbit does. The server sends, before every frame of
// a scene that cuts, where the box's corners and the plane's outline lie on that frame
// (projected with its own camera): this script draws them over the image. The
// plane's handle (a dot and a line towards the side kept) can be dragged along the
// normal on the image itself, and so can each face of the crop box (a square on the
// face's centre and a line along its outward normal): a face dragged moves along its
// axis (the box's min or max there).
// window.glint.cut exposes what was received and drawn, for the browser test.
"use strict";
(() => {
  const glint = window.glint;
  const frame = document.getElementById("frame");
  const overlay = document.createElement("canvas");
  overlay.id = "cut";
  overlay.setAttribute("aria-label", "crop box and clip plane");
  Object.assign(overlay.style, { position: "absolute", pointerEvents: "none", background: "transparent" });
  frame.after(overlay);
  const octx = overlay.getContext("2d");
  const AXES = ["x", "y", "z"];
  // The box's 12 edges: corners (bit a set: max along axis a) that differ in one bit.
  const EDGES = [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]];

  const state = (glint.cut = { bounds: null, last: null, drawn: 0, crop: null, plane: null, extra: [] });

  // The panel, built here so index.html only loads the script.
  const el = (tag, props = {}, ...kids) => { const e = Object.assign(document.createElement(tag), props); e.append(...kids); return e; };
  const slider = (id) => el("input", { id, type: "range", step: "any" });
  const cropOn = el("input", { id: "crop-on", type: "checkbox" });
  const clipOn = el("input", { id: "clip-on", type: "checkbox" });
  const clipAxis = el("select", { id: "clip-axis" }, ...AXES.map((a) => new Option(a, a)));
  const clipOffset = slider("clip-offset");
  const flip = el("button", { id: "clip-flip", type: "button", textContent: "flip" });
  const rows = AXES.map((a) => [slider(`crop-${a}-min`), slider(`crop-${a}-max`)]);
  const box = el("fieldset", { id: "cut-box", hidden: true },
    el("legend", { textContent: "Cut" }),
    el("label", {}, cropOn, " crop box"),
    ...rows.map(([lo, hi], a) => el("label", {}, `${AXES[a]} `, lo, hi)),
    el("label", {}, clipOn, " clip plane "),
    el("label", {}, "across ", clipAxis, " ", flip),
    el("label", {}, "offset ", clipOffset));
  document.getElementById("panel").insertBefore(box, document.getElementById("labels-box"));

  const send = (patch, interactive) => glint.update(patch, interactive);
  const cropPatch = () => ({ crop: cropOn.checked ? { min: rows.map((r) => Number(r[0].value)), max: rows.map((r) => Number(r[1].value)) } : null });
  // The page's plane is the scene's first; planes set otherwise (glint view --clip) follow it.
  const planePatch = () => {
    const planes = [...state.extra];
    if (clipOn.checked) {
      const a = AXES.indexOf(clipAxis.value);
      const point = state.bounds[0].map((lo, k) => (lo + state.bounds[1][k]) / 2);
      point[a] = Number(clipOffset.value);
      const normal = [0, 0, 0];
      normal[a] = state.flipped ? -1 : 1;
      planes.unshift({ point, normal });
    }
    return { clip: planes };
  };

  // A box slider never passes its partner: min stays below max by a 200th of the axis.
  function keepOrder(a, moved) {
    const [lo, hi] = rows[a];
    const gap = (state.bounds[1][a] - state.bounds[0][a]) / 200;
    if (Number(lo.value) > Number(hi.value) - gap) {
      if (moved === lo) lo.value = Number(hi.value) - gap; else hi.value = Number(lo.value) + gap;
    }
  }
  rows.forEach((pair, a) => pair.forEach((s) => {
    s.oninput = () => { keepOrder(a, s); if (!cropOn.checked) cropOn.checked = true; send(cropPatch(), true); };
    s.onchange = () => send(cropPatch(), false);
  }));
  cropOn.onchange = () => { send(cropPatch(), false); if (!cropOn.checked) clearIfUncut(); };
  clipOffset.oninput = () => { if (!clipOn.checked) clipOn.checked = true; send(planePatch(), true); };
  clipOffset.onchange = () => send(planePatch(), false);
  clipOn.onchange = () => { send(planePatch(), false); if (!clipOn.checked) clearIfUncut(); };
  clipAxis.onchange = () => { setOffsetRange(true); if (clipOn.checked) send(planePatch(), false); };
  flip.onclick = () => { state.flipped = !state.flipped; if (clipOn.checked) send(planePatch(), false); };

  function setOffsetRange(centre) {
    const a = AXES.indexOf(clipAxis.value);
    clipOffset.min = state.bounds[0][a];
    clipOffset.max = state.bounds[1][a];
    if (centre) clipOffset.value = (state.bounds[0][a] + state.bounds[1][a]) / 2;
  }

  // The controls from a scene (the starting one: glint view --crop/--clip).
  function fromScene(scene) {
    const b = state.bounds;
    rows.forEach(([lo, hi], a) => {
      for (const s of [lo, hi]) { s.min = b[0][a]; s.max = b[1][a]; }
      lo.value = scene.crop ? scene.crop.min[a] : b[0][a];
      hi.value = scene.crop ? scene.crop.max[a] : b[1][a];
    });
    cropOn.checked = Boolean(scene.crop);
    const planes = scene.clip || [];
    const first = planes[0];
    const axis = first ? first.normal.map(Math.abs).filter((x) => x > 0).length === 1 ? first.normal.findIndex((x) => x !== 0) : -1 : -1;
    if (axis >= 0) {
      clipOn.checked = true;
      clipAxis.value = AXES[axis];
      state.flipped = first.normal[axis] < 0;
      setOffsetRange(false);
      clipOffset.value = first.point[axis];
      state.extra = planes.slice(1);
    } else {
      state.extra = planes;
      setOffsetRange(true);
    }
  }

  function clearIfUncut() {
    if (!cropOn.checked && !clipOn.checked && state.extra.length === 0) { state.last = null; draw(); }
  }

  // Draws the last cut message's box and plane (fractions of the image) over the image.
  function draw() {
    overlay.style.left = `${frame.offsetLeft}px`;
    overlay.style.top = `${frame.offsetTop}px`;
    overlay.width = frame.clientWidth;
    overlay.height = frame.clientHeight;
    octx.clearRect(0, 0, overlay.width, overlay.height);
    const m = state.last;
    if (!m) return;
    const px = (p) => (p ? [p[0] * overlay.width, p[1] * overlay.height] : null);
    const line = (a, b) => { if (a && b) { octx.moveTo(...a); octx.lineTo(...b); } };
    octx.lineWidth = 1.5;
    if (m.crop) {
      const c = m.crop.map(px);
      octx.strokeStyle = "#0ff";
      octx.fillStyle = "#0ff";
      octx.beginPath();
      for (const [i, j] of EDGES) line(c[i], c[j]);
      octx.stroke();
      // The face handles: a line along the outward normal and a square on the centre.
      for (const face of m.faces || []) {
        const [h, t] = face.handle.map(px);
        if (!h || !t) continue;
        octx.beginPath();
        line(h, t);
        octx.stroke();
        octx.fillRect(h[0] - 4, h[1] - 4, 8, 8);
      }
    }
    octx.strokeStyle = "#f0f";
    octx.fillStyle = "#f0f";
    for (const plane of m.planes) {
      const o = plane.outline.map(px);
      octx.beginPath();
      o.forEach((p, i) => line(p, o[(i + 1) % o.length]));
      octx.stroke();
      const [h, t] = plane.handle.map(px);
      if (h && t) {
        octx.beginPath();
        line(h, t);
        octx.stroke();
        octx.beginPath();
        octx.arc(h[0], h[1], 6, 0, 2 * Math.PI);
        octx.fill();
      }
    }
    state.drawn += 1;
  }

  glint.hooks.message.push((msg) => {
    if (msg.type === "hello") {
      state.bounds = msg.bounds;
      box.hidden = !msg.bounds;
      if (msg.bounds) fromScene(msg.scene);
    } else if (msg.type === "cut") {
      state.last = msg;
      draw();
    } else if (msg.type === "scene") {
      state.crop = msg.scene.crop || null;
      state.plane = (msg.scene.clip || [])[0] || null;
      // A full frame that cuts nothing (or a split view): nothing to draw.
      const cuts = msg.scene.crop || (msg.scene.clip || []).length;
      if (!cuts || document.getElementById("split").value !== "off") { state.last = null; draw(); }
    }
  });

  // Dragging a handle on the image (the plane's, or a crop box face's) moves it along
  // its normal: the pointer's travel along the handle's line on the image, over the
  // line's length, is 15% of the bounds' diagonal (the handle's length in the world).
  // Of the handles within 10 pixels, the nearest that shows a direction (a face
  // seen edge-on cannot be dragged along its normal) is taken.
  let grab = null;
  const near = (e) => {
    const m = state.last;
    if (!m) return null;
    const r = frame.getBoundingClientRect();
    const onPage = (p) => [r.left + p[0] * r.width, r.top + p[1] * r.height];
    const found = [];
    const plane = clipOn.checked ? m.planes[0] : null;
    if (plane) found.push({ handle: plane.handle, face: -1 });
    if (cropOn.checked) (m.faces || []).forEach((f, i) => found.push({ handle: f.handle, face: i }));
    let best = null;
    for (const { handle, face } of found) {
      if (!handle[0] || !handle[1]) continue;
      const [h, t] = handle.map(onPage);
      const d = Math.hypot(e.clientX - h[0], e.clientY - h[1]);
      const len2 = (t[0] - h[0]) ** 2 + (t[1] - h[1]) ** 2;
      if (d <= 10 && len2 >= 4 && (!best || d < best.d)) best = { h, t, d, face };
    }
    return best;
  };
  frame.addEventListener("pointerdown", (e) => {
    const hit = near(e);
    if (!hit) return;
    // The handle, not the camera: app.js's orbit and pick.js's click stand aside.
    e.stopImmediatePropagation();
    frame.setPointerCapture(e.pointerId);
    const [dx, dy] = [hit.t[0] - hit.h[0], hit.t[1] - hit.h[1]];
    const b = state.bounds;
    const diagonal = Math.hypot(...b[1].map((x, k) => x - b[0][k]));
    const slider = hit.face >= 0 ? rows[hit.face >> 1][hit.face & 1] : clipOffset;
    grab = { x: e.clientX, y: e.clientY, dx, dy, len2: dx * dx + dy * dy, face: hit.face, slider,
      start: Number(slider.value), mm: 0.15 * diagonal };
    state.dragging = hit.face >= 0 ? `face ${hit.face}` : "plane";
  }, { capture: true });
  frame.addEventListener("pointermove", (e) => {
    if (!grab) return;
    e.stopImmediatePropagation();
    const along = ((e.clientX - grab.x) * grab.dx + (e.clientY - grab.y) * grab.dy) / grab.len2;
    const s = grab.slider;
    if (grab.face >= 0) {
      // Outwards is towards the tip: a max face grows with it, a min face shrinks.
      const sign = grab.face & 1 ? 1 : -1;
      s.value = Math.max(Number(s.min), Math.min(Number(s.max), grab.start + sign * along * grab.mm));
      keepOrder(grab.face >> 1, s);
      send(cropPatch(), true);
    } else {
      const sign = state.flipped ? -1 : 1;
      s.value = Math.max(Number(s.min), Math.min(Number(s.max), grab.start + sign * along * grab.mm));
      send(planePatch(), true);
    }
  }, { capture: true });
  frame.addEventListener("pointerup", (e) => {
    if (!grab) return;
    e.stopImmediatePropagation();
    send(grab.face >= 0 ? cropPatch() : planePatch(), false);
    grab = null;
    state.dragging = null;
  }, { capture: true });
  window.addEventListener("resize", draw);
})();
