// glint view: picking and measuring. A click on the image (pressed and released
// without dragging) asks the server for the 3D point that pixel shows; the server
// marks it (a second click makes a ruler to the first, a third starts again) and
// sends, before every frame, where the marks lie on that frame (projected with the
// frame's own camera), which this script draws over the image. The panel shows the
// last point's world mm, value and label, and the ruler's length.
// window.glint.pick exposes what was received and drawn, for the browser test.
"use strict";
(() => {
  const glint = window.glint;
  const frame = document.getElementById("frame");
  const overlay = document.createElement("canvas");
  overlay.id = "marks";
  overlay.setAttribute("aria-label", "picked points and ruler");
  Object.assign(overlay.style, { position: "absolute", pointerEvents: "none", background: "transparent", cursor: "default" });
  frame.after(overlay);
  const octx = overlay.getContext("2d");

  const box = document.createElement("fieldset");
  box.id = "pick-box";
  const legend = document.createElement("legend");
  legend.textContent = "Pick";
  const info = document.createElement("div");
  info.id = "pick-info";
  info.textContent = "click the image: a point; a second click: a ruler";
  const ruler = document.createElement("div");
  ruler.id = "pick-ruler";
  const clear = document.createElement("button");
  clear.type = "button";
  clear.textContent = "clear marks";
  clear.onclick = () => glint.send({ type: "unmark" });
  box.append(legend, info, ruler, clear);
  document.getElementById("panel").insertBefore(box, document.getElementById("samples"));

  const state = (glint.pick = { answers: 0, last: null, marks: [], points: [], distance: null, drawn: 0 });
  const fmt = (v) => v.map((x) => x.toFixed(1)).join(", ");

  // Draws the marks (fractions of the image) over the image as it is shown.
  function draw() {
    overlay.style.left = `${frame.offsetLeft}px`;
    overlay.style.top = `${frame.offsetTop}px`;
    overlay.width = frame.clientWidth;
    overlay.height = frame.clientHeight;
    const px = state.points.map((p) => (p ? [p[0] * overlay.width, p[1] * overlay.height] : null));
    octx.clearRect(0, 0, overlay.width, overlay.height);
    if (px.length === 2 && px[0] && px[1]) {
      octx.strokeStyle = "#ff0";
      octx.lineWidth = 2;
      octx.beginPath();
      octx.moveTo(...px[0]);
      octx.lineTo(...px[1]);
      octx.stroke();
      if (state.distance !== null) {
        const [mx, my] = [(px[0][0] + px[1][0]) / 2, (px[0][1] + px[1][1]) / 2];
        octx.font = "13px system-ui, sans-serif";
        octx.fillStyle = "#ff0";
        octx.fillText(`${state.distance.toFixed(1)} mm`, mx + 6, my - 6);
      }
    }
    for (const p of px) {
      if (!p) continue;
      octx.fillStyle = "#ff0";
      octx.strokeStyle = "#000";
      octx.lineWidth = 1.5;
      octx.beginPath();
      octx.arc(p[0], p[1], 5, 0, 2 * Math.PI);
      octx.fill();
      octx.stroke();
    }
    state.drawn += 1;
  }

  function showPick(p) {
    if (!p) { info.textContent = "nothing there"; return; }
    const what = p.object.kind === "mesh" ? `mesh ${p.object.index}` : p.object.kind.replace("_", " ");
    const lines = [`${what} at (${fmt(p.world_mm)}) mm`];
    if (p.voxel_nearest) lines.push(`voxel (${p.voxel_nearest.join(", ")})`);
    if (p.value !== null && p.value !== undefined) lines.push(`value ${p.value.toFixed(2)}${p.units ? ` ${p.units}` : ""}`);
    if (p.label) lines.push(`label ${p.label.id}: ${p.label.name}`);
    info.textContent = lines.join(" · ");
  }

  glint.hooks.message.push((msg) => {
    if (msg.type === "pick") {
      state.answers += 1;
      state.last = msg.pick;
      state.marks = msg.marks;
      state.distance = msg.distance_mm;
      showPick(msg.pick);
      ruler.textContent = msg.distance_mm === null ? "" : `ruler: ${msg.distance_mm.toFixed(2)} mm`;
    } else if (msg.type === "marks") {
      state.points = msg.points;
      state.distance = msg.distance_mm;
      if (msg.points.length === 0) { state.marks = []; info.textContent = ""; ruler.textContent = ""; }
      draw();
    }
  });

  // A click is a press and release less than 4 px apart (more is a drag, which orbits).
  let down = null;
  frame.addEventListener("pointerdown", (e) => { down = { x: e.clientX, y: e.clientY }; });
  frame.addEventListener("pointerup", (e) => {
    if (!down) return;
    const moved = Math.hypot(e.clientX - down.x, e.clientY - down.y);
    down = null;
    if (moved >= 4) return;
    // The canvas holds the last full frame at the scene's full resolution.
    const r = frame.getBoundingClientRect();
    const x = ((e.clientX - r.left) / r.width) * frame.width;
    const y = ((e.clientY - r.top) / r.height) * frame.height;
    glint.send({ type: "pick", x, y });
  });
  window.addEventListener("resize", draw);
})();
