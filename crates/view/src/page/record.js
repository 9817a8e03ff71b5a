// glint view: the "Record" box. Records a turntable of the current scene on the server
// (N views round it, rendered by the code of `glint render --turntable`, at the
// scene's size) as a GIF, a WebP or (when the server has ffmpeg) an MP4: the page
// shows the server's progress, then offers the file for download. The server sends a
// "recorded" message, then the file as the next binary message.
// window.glint.record exposes what was received, for the browser test.
"use strict";
(() => {
  const glint = window.glint;
  const el = (tag, props = {}, ...kids) => { const e = Object.assign(document.createElement(tag), props); e.append(...kids); return e; };
  const frames = el("input", { id: "record-frames", type: "number", min: 2, max: 360, step: 1, value: 36 });
  const format = el("select", { id: "record-format" });
  const button = el("button", { id: "record", type: "button", textContent: "record" });
  const progress = el("progress", { id: "record-progress", max: 100, value: 0, hidden: true });
  const link = el("a", { id: "record-link", hidden: true, textContent: "download" });
  const box = el("fieldset", { id: "record-box" },
    el("legend", { textContent: "Record" }),
    el("label", {}, "frames ", frames), " ",
    el("label", {}, "as ", format), " ", button, " ", progress, " ", link);
  document.getElementById("save").after(box);

  const state = (glint.record = { percent: 0, progress: [], recorded: null, bytes: null, busy: false });
  const NAMES = { gif: "GIF", webp: "WebP", mp4: "MP4" };
  const TYPES = { gif: "image/gif", webp: "image/webp", mp4: "video/mp4" };

  button.onclick = () => {
    state.busy = true;
    state.recorded = null;
    state.bytes = null;
    state.progress = [];
    button.disabled = true;
    progress.hidden = false;
    progress.value = 0;
    link.hidden = true;
    glint.send({ type: "record", frames: Number(frames.value), format: format.value });
  };

  glint.hooks.message.push((msg) => {
    if (msg.type === "hello") {
      format.replaceChildren(...(msg.record || []).map((f) => new Option(NAMES[f] || f, f)));
    } else if (msg.type === "recording") {
      state.percent = msg.percent;
      state.progress.push(msg.percent);
      progress.value = msg.percent;
    } else if (msg.type === "recorded") {
      state.recorded = msg;
    } else if (msg.type === "error" && state.busy && !state.recorded) {
      // The recording was refused or failed: the error line is shown by app.js.
      state.busy = false;
      button.disabled = false;
      progress.hidden = true;
    }
  });

  // The binary message after "recorded" is the file.
  glint.hooks.binary.push((data) => {
    const r = state.recorded;
    if (!r || !state.busy) return false;
    state.busy = false;
    state.bytes = data;
    if (link.href) URL.revokeObjectURL(link.href);
    link.href = URL.createObjectURL(new Blob([data], { type: TYPES[r.format] || "application/octet-stream" }));
    link.download = `glint-turntable.${r.format}`;
    link.textContent = `download ${NAMES[r.format] || r.format} (${r.frames} frames, ${Math.round(r.bytes / 1024)} KiB)`;
    link.hidden = false;
    progress.hidden = true;
    button.disabled = false;
    return true;
  });
})();
