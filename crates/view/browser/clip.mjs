// Drives glint view's "Cut" panel in Debian's headless Chromium through playwright-core
// (as drive.mjs):
//
//   node clip.mjs test URL [SHOT.png]   tick the crop box, drag the x max slider to the
//                                       volume's middle; report the frame's pixels per
//                                       half before and after, the overlay's box, the
//                                       server's scene; then tick the clip plane and
//                                       drag its handle half its length towards its tip;
//                                       before that, drag the box's x min face handle
//                                       inwards, the frames before and after kept;
//                                       at the end, record a 4-frame GIF (its bytes
//                                       in the report)
//   node clip.mjs bench URL SECONDS     tick the clip plane and sweep its offset slider
//                                       for SECONDS (an input event every 16 ms):
//                                       frames/s received, input-to-frame latency
//
// Prints one JSON line; exits non-zero on failure.
import { chromium } from "playwright-core";

const [mode, url, arg] = process.argv.slice(2);
if (!["test", "bench"].includes(mode) || !url) {
  console.error("usage: clip.mjs test URL [SHOT.png] | clip.mjs bench URL SECONDS");
  process.exit(2);
}
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
try {
  const page = await browser.newPage({ viewport: { width: 900, height: 640 } });
  page.on("pageerror", (e) => { console.error(`page error: ${e.message}`); process.exitCode = 1; });
  await page.goto(url);
  await page.waitForFunction(() => window.glint && window.glint.full >= 1 && window.glint.cut.bounds, null, { timeout: 120000 });
  // Waits for the full frame after `act`.
  const afterFrame = async (act) => {
    const full = await page.evaluate(() => window.glint.full);
    await act();
    await page.waitForFunction((n) => window.glint.full > n, full, { timeout: 120000 });
  };
  if (process.env.GLINT_VIEW) {
    // Start from a named view (the benchmark's scene, as drive.mjs).
    await afterFrame(() => page.click(`#views button:text-is("${process.env.GLINT_VIEW}")`));
  }
  if (mode === "test") {
    const visible = await page.locator("#cut-box").isVisible();
    const keep = () => page.evaluate(() => {
      const f = document.getElementById("frame");
      window.__kept = window.__kept || [];
      window.__kept.push(f.getContext("2d").getImageData(0, 0, f.width, f.height));
    });
    await keep();
    await afterFrame(() => page.locator("#crop-on").check());
    const ticked = await page.evaluate(() => window.glint.scene.crop);
    // A drag of the x max slider from the bounds to the middle: input events (each
    // an interactive patch), then the change that ends it.
    const bounds = await page.evaluate(() => window.glint.cut.bounds);
    const middle = (bounds[0][0] + bounds[1][0]) / 2;
    await afterFrame(() => page.evaluate(async ([from, to]) => {
      const s = document.getElementById("crop-x-max");
      for (let i = 1; i <= 8; i++) {
        s.value = from + ((to - from) * i) / 8;
        s.dispatchEvent(new Event("input", { bubbles: true }));
        await new Promise((r) => setTimeout(r, 30));
      }
      s.dispatchEvent(new Event("change", { bubbles: true }));
    }, [bounds[1][0], middle]));
    await page.waitForFunction((m) => { const c = window.glint.scene.crop; return c && Math.abs(c.max[0] - m) < 1e-6; }, middle, { timeout: 120000 });
    await keep();
    // Per half of the frame (a tenth of the width either side of the middle left
    // out): mean grey before, after, and the mean absolute change.
    const halves = await page.evaluate(() => {
      const [a, b] = window.__kept;
      const w = a.width, h = a.height, out = {};
      for (const [name, x0, x1] of [["left", 0, Math.floor(0.4 * w)], ["right", Math.ceil(0.6 * w), w]]) {
        let before = 0, after = 0, diff = 0, n = 0;
        for (let y = 0; y < h; y++) for (let x = x0; x < x1; x++) {
          const i = 4 * (y * w + x);
          const g0 = (a.data[i] + a.data[i + 1] + a.data[i + 2]) / 3, g1 = (b.data[i] + b.data[i + 1] + b.data[i + 2]) / 3;
          before += g0; after += g1; diff += Math.abs(g1 - g0); n += 1;
        }
        out[name] = { before: before / n, after: after / n, diff: diff / n };
      }
      // The background: the top-left pixel of the first frame.
      out.background = (a.data[0] + a.data[1] + a.data[2]) / 3;
      return out;
    });
    const cut = await page.evaluate(() => ({ last: window.glint.cut.last, drawn: window.glint.cut.drawn, scene: window.glint.scene.crop }));
    // The overlay's alpha at fractions (fx, fy) of the image, the most in a 5x5 patch.
    const alphaAt = (fx, fy) => page.evaluate(([fx, fy]) => {
      const o = document.getElementById("cut");
      const x = Math.round(fx * o.width), y = Math.round(fy * o.height);
      const d = o.getContext("2d").getImageData(Math.max(0, x - 2), Math.max(0, y - 2), 5, 5).data;
      let a = 0;
      for (let i = 3; i < d.length; i += 4) a = Math.max(a, d[i]);
      return a;
    }, [fx, fy]);
    // Every edge of the box seen on the image: drawn at its middle.
    const edges = [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]];
    const c = cut.last ? cut.last.crop : null;
    const onEdges = [];
    if (c) for (const [i, j] of edges) {
      const m = [(c[i][0] + c[j][0]) / 2, (c[i][1] + c[j][1]) / 2];
      if (m.every((v) => v > 0.02 && v < 0.98)) onEdges.push(await alphaAt(...m));
    }
    const xs = c ? c.map((p) => p[0]) : [];
    const boxX = [Math.min(...xs), Math.max(...xs)];
    // A face handle: the box's x min face (face 0) dragged on the image 90% of its
    // handle's length inwards (away from its tip); the strip of the image between
    // the face's old and new place goes dark, the rest of the box is unchanged.
    const faceStart = await page.evaluate(() => ({ crop: window.glint.scene.crop, handle: window.glint.cut.last.faces[0].handle }));
    const faceDrawn = await alphaAt(...faceStart.handle[0]);
    await page.locator("#frame").scrollIntoViewIfNeeded();
    {
      const fb = await page.locator("#frame").boundingBox();
      const at = (p) => [fb.x + p[0] * fb.width, fb.y + p[1] * fb.height];
      const [[hx, hy], [tx, ty]] = faceStart.handle.map(at);
      await afterFrame(async () => {
        await page.mouse.move(hx, hy);
        await page.mouse.down();
        await page.mouse.move(hx - 0.9 * (tx - hx), hy - 0.9 * (ty - hy), { steps: 6 });
        await page.mouse.up();
      });
    }
    await page.waitForFunction((x) => window.glint.scene.crop.min[0] !== x, faceStart.crop.min[0], { timeout: 120000 });
    await page.waitForFunction(() => window.glint.cut.last && window.glint.cut.last.faces, null, { timeout: 120000 });
    await keep();
    const faceEnd = await page.evaluate(() => ({ crop: window.glint.scene.crop, handle: window.glint.cut.last.faces[0].handle,
      camera: window.glint.scene.camera, picks: window.glint.pick.answers }));
    // Columns (fractions of the width) of the strip cut away and of the box still
    // kept, two pixels in from each edge; per region the mean and most grey before
    // and after the drag, and the mean absolute change.
    const faceRegions = await page.evaluate(([a0, a1, keptEnd]) => {
      const [, a, b] = window.__kept;
      const w = a.width, h = a.height;
      const cols = (u, v) => [Math.ceil(Math.min(u, v) * w) + 2, Math.floor(Math.max(u, v) * w) - 2];
      const stats = ([x0, x1]) => {
        let before = 0, after = 0, most = 0, diff = 0, n = 0;
        for (let y = 0; y < h; y++) for (let x = x0; x <= x1; x++) {
          const i = 4 * (y * w + x);
          const g0 = (a.data[i] + a.data[i + 1] + a.data[i + 2]) / 3, g1 = (b.data[i] + b.data[i + 1] + b.data[i + 2]) / 3;
          before += g0; after += g1; most = Math.max(most, g0); diff += Math.abs(g1 - g0); n += 1;
        }
        return { columns: [x0, x1], before: before / n, after: after / n, most_before: most, diff: diff / n };
      };
      return { strip: stats(cols(a0, a1)), rest: stats(cols(a1, keptEnd)) };
    }, [faceStart.handle[0][0], faceEnd.handle[0][0], faceStart.handle[0][0] < 0.5 ? boxX[1] : boxX[0]]);
    const face = { start: faceStart, end: faceEnd, drawn: faceDrawn, regions: faceRegions };
    // The clip plane: ticked, its handle drawn; dragging the handle half its length
    // towards its tip moves the plane along its normal.
    await afterFrame(() => page.locator("#clip-on").check());
    await page.waitForFunction(() => (window.glint.scene.clip || []).length === 1 && window.glint.cut.last.planes.length === 1, null, { timeout: 120000 });
    const plane = await page.evaluate(() => ({ start: window.glint.scene.clip[0], handle: window.glint.cut.last.planes[0].handle }));
    const [h, t] = plane.handle;
    const handleDrawn = await alphaAt(...h);
    // Ticking the box scrolled the panel into view: the image back into view first.
    await page.locator("#frame").scrollIntoViewIfNeeded();
    const fb = await page.locator("#frame").boundingBox();
    const at = (p) => [fb.x + p[0] * fb.width, fb.y + p[1] * fb.height];
    const [[hx, hy], [tx, ty]] = [at(h), at(t)];
    await afterFrame(async () => {
      await page.mouse.move(hx, hy);
      await page.mouse.down();
      await page.mouse.move(hx + (tx - hx) / 2, hy + (ty - hy) / 2, { steps: 5 });
      await page.mouse.up();
    });
    await page.waitForFunction((x) => window.glint.scene.clip[0].point[0] !== x, plane.start.point[0], { timeout: 120000 });
    const dragged = await page.evaluate(() => ({ plane: window.glint.scene.clip[0], camera: window.glint.scene.camera, picks: window.glint.pick.answers }));
    // The record button: a 4-frame GIF of the scene (the plane off again: with it,
    // nothing is left of the ball), rendered by the server; the page shows the
    // progress and offers the file, whose bytes come back to the test to be decoded.
    await afterFrame(() => page.locator("#clip-on").uncheck());
    await page.locator("#record-frames").fill("4");
    await page.selectOption("#record-format", "gif");
    await page.click("#record");
    await page.waitForFunction(() => window.glint.record.bytes !== null || window.glint.errors.length > 0, null, { timeout: 120000 });
    const record = await page.evaluate(() => {
      const r = window.glint.record, link = document.getElementById("record-link");
      return { recorded: r.recorded, progress: r.progress, bytes: r.bytes ? Array.from(new Uint8Array(r.bytes)) : null,
        link: { shown: !link.hidden, download: link.download, href: link.href.slice(0, 5) },
        formats: [...document.getElementById("record-format").options].map((o) => o.value),
        scene: window.glint.scene.size };
    });
    if (arg) await page.screenshot({ path: arg });
    const errors = await page.evaluate(() => window.glint.errors);
    const report = { visible, ticked, bounds, middle, halves, crop: cut.scene, box_x: boxX, edges: onEdges, drawn: cut.drawn,
      plane: plane.start, handle: plane.handle, handle_drawn: handleDrawn, dragged, face, record, errors };
    console.log(JSON.stringify(report));
    if (!visible || errors.length || !c || onEdges.length === 0) process.exitCode = 1;
  } else {
    const seconds = Number(arg || 5);
    await afterFrame(() => page.locator("#clip-on").check());
    await page.evaluate(() => { window.glint.latencies.length = 0; });
    const f0 = await page.evaluate(() => window.glint.frames);
    const t0 = Date.now();
    let i = 0;
    // A steady sweep: one input event every 16 ms, over the middle 60% of the range.
    while (Date.now() - t0 < seconds * 1000) {
      i += 1;
      await page.evaluate((i) => {
        const s = document.getElementById("clip-offset");
        const [lo, hi] = [Number(s.min), Number(s.max)];
        s.value = lo + (hi - lo) * (0.5 + 0.3 * Math.sin(i / 20));
        s.dispatchEvent(new Event("input", { bubbles: true }));
      }, i);
      await new Promise((r) => setTimeout(r, 16));
    }
    const elapsed = (Date.now() - t0) / 1000;
    const f1 = await page.evaluate(() => window.glint.frames);
    const lat = (await page.evaluate(() => window.glint.latencies.slice())).sort((a, b) => a - b);
    const q = (p) => lat.length ? lat[Math.min(lat.length - 1, Math.floor(p * lat.length))] : NaN;
    const errors = await page.evaluate(() => window.glint.errors);
    console.log(JSON.stringify({ seconds: elapsed, events: i, frames: f1 - f0,
      fps: (f1 - f0) / elapsed, latency_ms_p50: q(0.5), latency_ms_p95: q(0.95), samples: lat.length, errors }));
    if (errors.length) process.exitCode = 1;
  }
} finally {
  await browser.close();
}
