// Drives glint.Viewer inside JupyterLab in Debian's headless Chromium (no browser
// download), for scripts/notebook-screenshot:
//
//   node lab.mjs URL SCREENSHOT.png     open the notebook at URL (JupyterLab, with its
//                                       token), run all cells, wait for the viewer's
//                                       first frame, drag on it, check the image
//                                       changed, write the screenshot
//
// Prints one JSON line; exits non-zero on failure.
import { chromium } from "playwright-core";

const [url, shot] = process.argv.slice(2);
if (!url || !shot) {
  console.error("usage: lab.mjs URL SCREENSHOT.png");
  process.exit(2);
}
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 900 } });
  await page.goto(url);
  // JupyterLab is up and the notebook's kernel idle.
  await page.waitForSelector(".jp-Notebook", { timeout: 120000 });
  await page.waitForSelector(".jp-Notebook-ExecutionIndicator[data-status='idle']", { timeout: 120000 }).catch(() => {});
  await page.click(".jp-Notebook");
  // Run > Run All Cells, through JupyterLab's command (the menu's own).
  await page.keyboard.press("Escape");
  await page.click("text=Run", { timeout: 30000 });
  await page.click("text=Run All Cells", { timeout: 30000 });
  // The viewer's image: jupyter_rfb's <img class="renderview-view">, with a frame.
  const img = page.locator("img.renderview-view").first();
  await img.waitFor({ timeout: 180000 });
  const src = async () => img.evaluate((e) => e.src);
  await page.waitForFunction(() => {
    const e = document.querySelector("img.renderview-view");
    return e && e.src && e.naturalWidth > 16;
  }, null, { timeout: 180000 });
  // Let the notebook finish (the snapshot cell).
  await page.waitForFunction(() => document.querySelectorAll(".jp-OutputArea-output img").length >= 1,
    null, { timeout: 180000 }).catch(() => {});
  await img.scrollIntoViewIfNeeded();
  await page.waitForTimeout(1500);
  const before = await img.screenshot();
  const box = await img.boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  for (let i = 1; i <= 20; i++) {
    await page.mouse.move(cx + i * 6, cy + i * 2);
    await page.waitForTimeout(30);
  }
  await page.mouse.up();
  await page.waitForTimeout(2500);
  const after = await img.screenshot();
  const changed = Buffer.compare(before, after) !== 0;
  await page.locator(".jp-Cell").nth(1).scrollIntoViewIfNeeded();
  await page.screenshot({ path: shot });
  console.log(JSON.stringify({ changed, width: box.width, height: box.height, src: (await src()).slice(0, 16) }));
  if (!changed) process.exitCode = 1;
} finally {
  await browser.close();
}
