// Opens a campaign's report.html in headless Chromium and checks it as a user would:
//   node tests/browser/report.test.mjs REPORT_HTML EXPECTED_TESTS SCREENSHOT_PNG [--load-only]
// (--load-only: the load, request and point checks, then the screenshot)
// - the page loads with no console error and no request besides the file itself;
// - the map draws one point per test, and the settings name the system under test;
// - changing the x-axis menu redraws the map on the new parameter;
// - the robustness colouring draws the diverging scale's legend;
// - clicking a failed point, and a row of the failure table, shows that test's replay command;
// - the failure table sorts by robustness.
// Prints one JSON line of what it saw; exits 1 on the first failed check.
import { chromium } from "playwright-core";
import { pathToFileURL } from "node:url";
import path from "node:path";

const [reportPath, expectedArg, screenshot, mode] = process.argv.slice(2);
const loadOnly = mode === "--load-only";
if (!reportPath || !expectedArg || !screenshot) {
  console.error("usage: report.test.mjs REPORT_HTML EXPECTED_TESTS SCREENSHOT_PNG");
  process.exit(2);
}
const expected = Number(expectedArg);
const url = pathToFileURL(path.resolve(reportPath)).href;
const seen = { consoleErrors: [], requests: [] };
const check = (ok, what) => {
  if (!ok) {
    console.error("FAILED: " + what + "\n" + JSON.stringify(seen));
    process.exit(1);
  }
};

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
  ],
});
try {
  const page = await browser.newPage({ viewport: { width: 1400, height: 1000 } });
  page.on("console", (m) => { if (m.type() === "error") seen.consoleErrors.push(m.text()); });
  page.on("pageerror", (e) => seen.consoleErrors.push(String(e)));
  page.on("request", (r) => seen.requests.push(r.url()));
  await page.goto(url);
  await page.waitForFunction(() => window.paracosmReport && window.paracosmReport.redraws >= 1, null, { timeout: 30000 });

  const others = seen.requests.filter((u) => u !== url && !u.startsWith("data:"));
  check(others.length === 0, "requests besides the file: " + others.join(", "));
  check(seen.consoleErrors.length === 0, "console errors");

  // One point per test, in the DOM (SVG renderer) and in Vega's scene graph.
  seen.domPoints = await page.locator("#map g.mark-symbol.role-mark path").count();
  seen.scenePoints = await page.evaluate(() => window.paracosmReport.pointsDrawn());
  check(seen.domPoints === expected, `points drawn ${seen.domPoints} != tests ${expected}`);
  check(seen.scenePoints === expected, `scene points ${seen.scenePoints} != tests ${expected}`);
  // The settings name the system under test that ran.
  seen.settings = await page.locator("#settings").textContent();
  check(seen.settings.includes("system under test"), "the settings do not name the system under test");
  if (loadOnly) {
    await page.screenshot({ path: screenshot, fullPage: true });
    console.log(JSON.stringify(seen));
    process.exit(0);
  }

  // Changing the x axis redraws on the chosen parameter.
  const axisTitles = () => page.locator("#map g.role-axis-title text").allTextContents();
  seen.titlesBefore = await axisTitles();
  const options = await page.locator("#x-axis option").evaluateAll((os) => os.map((o) => [o.value, o.textContent]));
  const current = await page.locator("#x-axis").inputValue();
  const y = await page.locator("#y-axis").inputValue();
  const [value, text] = options.find(([v]) => v !== current && v !== y);
  await page.selectOption("#x-axis", value);
  await page.waitForFunction(() => window.paracosmReport.redraws >= 2);
  seen.titlesAfter = await axisTitles();
  check(seen.titlesAfter.includes(text) && !seen.titlesBefore.includes(text), `x axis title is not "${text}" after the change`);
  check(await page.locator("#map g.mark-symbol.role-mark path").count() === expected, "points after the redraw");
  await page.selectOption("#x-axis", current);
  await page.waitForFunction(() => window.paracosmReport.redraws >= 3);

  // Colour by robustness: the legend shows the robustness scale.
  await page.selectOption("#color", "robustness");
  await page.waitForFunction(() => window.paracosmReport.redraws >= 4);
  seen.legends = await page.locator("#map g.role-legend-title text").allTextContents();
  check(seen.legends.includes("robustness"), "no robustness legend");

  // Clicking a failed point shows its replay command.
  // The first failed item of the map's symbol mark, and the same item's path in the SVG.
  const target = await page.evaluate(() => {
    let mark = null;
    const walk = (node) => {
      if (!node || mark) return;
      if (node.marktype === "symbol" && node.role === "mark") { mark = node; return; }
      (node.items || []).forEach(walk);
    };
    walk(window.paracosmReport.view.scenegraph().root);
    const k = mark ? mark.items.findIndex((i) => i.datum && i.datum.status === "fail") : -1;
    if (k < 0) return null;
    const pathEl = document.querySelectorAll("#map g.mark-symbol.role-mark path")[k];
    pathEl.scrollIntoView({ block: "center" });
    const box = pathEl.getBoundingClientRect();
    return { id: mark.items[k].datum.id, x: box.left + box.width / 2, y: box.top + box.height / 2 };
  });
  check(target !== null, "no failed point to click");
  seen.target = target;
  seen.under = await page.evaluate(([x, y]) => { const e = document.elementFromPoint(x, y); return e ? e.outerHTML.slice(0, 200) : null; }, [target.x, target.y]);
  await page.mouse.click(target.x, target.y);
  await page.waitForSelector("#replay-command", { timeout: 3000 }).catch(() => check(false, "no replay command after clicking a failed point"));
  seen.clickedId = target.id;
  seen.replay = await page.locator("#replay-command").textContent();
  check(seen.replay.includes(` --id ${target.id} `) && seen.replay.startsWith("paracosm-fuzz replay "), "clicking a failure does not show its replay command");

  // The failure table sorts by robustness, and a row shows its test.
  const robustnessColumn = async () => (await page.locator("#failures tbody tr td:nth-child(2)").allTextContents()).map(Number);
  const ascending = await robustnessColumn();
  check(ascending.length > 1 && ascending.every((x, i) => i === 0 || ascending[i - 1] <= x), "failures not sorted by robustness");
  await page.locator("#failures thead th", { hasText: "robustness" }).click();
  const descending = await robustnessColumn();
  check(descending.every((x, i) => i === 0 || descending[i - 1] >= x), "failures not sorted by robustness, descending");
  await page.locator("#failures thead th", { hasText: "robustness" }).click();
  const row = page.locator("#failures tbody tr").nth(1);
  const rowId = await row.getAttribute("data-id");
  await row.click();
  const rowReplay = await page.locator("#replay-command").textContent();
  check(rowReplay.includes(` --id ${rowId} `), "clicking a row does not show its replay command");

  check(seen.consoleErrors.length === 0, "console errors after the interactions");
  check(seen.requests.filter((u) => u !== url && !u.startsWith("data:")).length === 0, "requests after the interactions");
  await page.selectOption("#color", "outcome");
  await page.waitForFunction(() => window.paracosmReport.redraws >= 5);
  await page.evaluate((id) => window.paracosmReport.show(id), target.id);
  await page.screenshot({ path: screenshot, fullPage: true });
  console.log(JSON.stringify(seen));
} finally {
  await browser.close();
}
