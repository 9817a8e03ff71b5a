// Opens a glint batch report (index.html) from the disk in Debian's headless Chromium,
// through the playwright-core that crates/view/browser installs (one browser stack for
// the project; no browser download: /usr/bin/chromium or $CHROMIUM).
//
//   node report.mjs /path/to/index.html SCREENSHOT.png
//
// Prints one JSON line: the thumbnails (all, and those whose PNG decoded), the failed
// cards and their error lines, the ids after sorting by subject, requests that left
// the disk, page errors. Exits non-zero when the page cannot be loaded.
import { createRequire } from "node:module";
import { pathToFileURL } from "node:url";

const require = createRequire(new URL("../../view/browser/package.json", import.meta.url));
const { chromium } = require("playwright-core");

const [report, shot] = process.argv.slice(2);
if (!report || !shot) {
  console.error("usage: report.mjs INDEX.html SCREENSHOT.png");
  process.exit(2);
}
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
});
try {
  const page = await browser.newPage({ viewport: { width: 1000, height: 700 } });
  const errors = [];
  const remote = [];
  page.on("pageerror", (e) => errors.push(e.message));
  page.on("request", (r) => { if (!r.url().startsWith("file:")) remote.push(r.url()); });
  await page.goto(pathToFileURL(report).href);
  // Lazy thumbnails load when scrolled to: bring each into view, then wait for all.
  for (const img of await page.locator("img.thumb").all()) await img.scrollIntoViewIfNeeded();
  await page.waitForFunction(() => Array.from(document.images).every((i) => i.complete), null, { timeout: 60000 });
  const state = await page.evaluate(() => {
    const thumbs = Array.from(document.querySelectorAll("img.thumb"));
    return {
      thumbnails: thumbs.length,
      decoded: thumbs.filter((i) => i.naturalWidth > 0).length,
      failed: Array.from(document.querySelectorAll(".card.failed")).map((c) => ({
        id: c.dataset.id, error: c.querySelector(".error")?.textContent ?? "" })),
    };
  });
  await page.click('#controls button[data-sort="subject"]');
  const bySubject = await page.evaluate(() =>
    Array.from(document.querySelectorAll(".card")).map((c) => c.dataset.id));
  await page.check("#only-failed");
  const visible = await page.evaluate(() =>
    Array.from(document.querySelectorAll(".card")).filter((c) => c.offsetParent !== null).length);
  await page.uncheck("#only-failed");
  await page.screenshot({ path: shot, fullPage: true });
  console.log(JSON.stringify({ ...state, bySubject, visibleWhenOnlyFailed: visible, remote, errors }));
} finally {
  await browser.close();
}
