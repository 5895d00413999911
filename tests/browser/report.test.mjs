// Browser tests of `lagrange report` pages, in Debian's headless Chromium.
//
//     cd tests/browser && npm install && node --test
//
// Every .html file in the folder $LAGRANGE_REPORTS (default: pages made here, in out/,
// from the samples in crates/view/src/report/samples/ by tools/report_page.py) is loaded
// and checked: no console errors or warnings and no page errors, no request leaves the
// file, the animation advances while playing, `seek` shows a row exactly and interpolates
// between rows, hovering a plot shows a readout, and (3-D) dragging turns the camera.
// Next to each page the test writes NAME.positions.json (the positions the page draws at
// a chosen row's time, for the Rust side to compare with the run's CSV) and NAME.png (a
// screenshot of the whole page at that time).

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdirSync, readdirSync, writeFileSync } from 'node:fs';
import { basename, dirname, join, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

const here = dirname(fileURLToPath(import.meta.url));
const root = resolve(here, '..', '..');

const CHROMIUM_ARGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
];
const WAIT_MS = 20_000; // generous: the machine is shared; nothing here measures speed

/** The folder of pages to test: $LAGRANGE_REPORTS, or pages made from the samples. */
function reportsFolder() {
  if (process.env.LAGRANGE_REPORTS) return resolve(process.env.LAGRANGE_REPORTS);
  const samples = join(root, 'crates', 'view', 'src', 'report', 'samples');
  const out = join(here, 'out');
  mkdirSync(out, { recursive: true });
  for (const sample of readdirSync(samples).filter((f) => f.endsWith('.json'))) {
    const page = join(out, basename(sample, '.json') + '.html');
    execFileSync('python3', [join(root, 'tools', 'report_page.py'), join(samples, sample), page]);
  }
  return out;
}

const folder = reportsFolder();
const pages = readdirSync(folder).filter((f) => f.endsWith('.html')).sort();

let browser;
before(async () => {
  browser = await chromium.launch({ executablePath: '/usr/bin/chromium', args: CHROMIUM_ARGS });
});
after(async () => {
  await browser?.close();
});

test('there are report pages to test', () => {
  assert.ok(pages.length > 0, `no .html files in ${folder}`);
});

for (const file of pages) {
  test(`report page ${file}`, async () => {
    const context = await browser.newContext({ viewport: { width: 1200, height: 900 }, deviceScaleFactor: 1 });
    try {
      await checkPage(await context.newPage(), file);
    } finally {
      await context.close();
    }
  });
}

/** All the checks of one page; `file` is its name in the folder. */
async function checkPage(page, file) {
  const problems = [];
  page.on('console', (message) => {
    if (message.type() === 'error' || message.type() === 'warning') {
      problems.push(`console ${message.type()}: ${message.text()}`);
    }
  });
  page.on('pageerror', (error) => problems.push(`page error: ${error.message}`));
  page.on('request', (request) => {
    const url = request.url();
    if (!url.startsWith('file:') && !url.startsWith('data:')) problems.push(`request to ${url}`);
  });

  const path = join(folder, file);
  await page.goto(pathToFileURL(path).href);
  await page.waitForFunction(() => window.lagrangeReport !== undefined, null, { timeout: WAIT_MS });
  const data = await page.evaluate(() => JSON.parse(document.getElementById('lagrange-data').textContent));
  assert.equal(data.format, 'lagrange.report/1');
  const api = await page.evaluate(() => Object.keys(window.lagrangeReport).sort());
  assert.deepEqual(api, ['pause', 'play', 'positions', 'seek', 'time']);

  await checkAnimationAdvances(page, data);
  const shown = await checkSeek(page, data);
  writeFileSync(join(folder, basename(file, '.html') + '.positions.json'), JSON.stringify(shown, null, 1) + '\n');
  await page.evaluate((t) => window.lagrangeReport.seek(t), shown.time);
  await page.screenshot({ path: join(folder, basename(file, '.html') + '.png'), fullPage: true });
  await exercisePage(page, data);

  assert.deepEqual(problems, [], `${file}: the page reported problems`);
}

/**
 * While playing, the shown time changes and so does the picture: the mechanism canvas
 * (below the time written in its corner) or, for a model with nothing to draw, the plots
 * with their time markers.
 */
async function checkAnimationAdvances(page, data) {
  if (data.time.length < 2 || !(data.until > 0)) return;
  await page.evaluate(() => {
    window.lagrangeReport.pause();
    window.lagrangeReport.seek(0);
    window.lagrangeReport.play();
  });
  const picture = data.points.length ? page.locator('#mechanism') : page.locator('#plots');
  const box = await picture.boundingBox();
  const clip = data.points.length
    ? { x: box.x, y: box.y + 30, width: box.width, height: box.height - 30 }
    : { x: box.x, y: box.y, width: box.width, height: Math.min(box.height, 600) };
  const first = { time: await page.evaluate(() => window.lagrangeReport.time()), png: await page.screenshot({ clip }) };
  await page
    .waitForFunction((t) => window.lagrangeReport.time() > t + 0.05, first.time, { timeout: WAIT_MS })
    .catch(() => assert.fail(`the shown time stays at ${first.time} while playing`));
  // The picture follows the time at the next frame the browser draws, and a slow start
  // moves little: look again until it differs, or give up after WAIT_MS.
  let second;
  const until = Date.now() + WAIT_MS;
  do {
    await page.waitForTimeout(100);
    second = { time: await page.evaluate(() => window.lagrangeReport.time()), png: await page.screenshot({ clip }) };
  } while (first.png.equals(second.png) && Date.now() < until);
  assert.notEqual(second.time, first.time, 'the shown time does not advance while playing');
  assert.ok(!first.png.equals(second.png), 'the picture does not change while playing');
  await page.evaluate(() => window.lagrangeReport.pause());
}

/**
 * `seek` to a row's time shows exactly that row's positions; half-way between two rows
 * it shows their mean. Returns what the page draws at the chosen row's time.
 */
async function checkSeek(page, data) {
  await page.evaluate(() => window.lagrangeReport.pause());
  if (!data.time.length) {
    return { time: 0, row: null, positions: await page.evaluate(() => window.lagrangeReport.positions()) };
  }
  const row = Math.floor((data.time.length - 1) / 3);
  const t = data.time[row];
  const shown = await page.evaluate((t) => {
    window.lagrangeReport.seek(t);
    return { time: window.lagrangeReport.time(), positions: window.lagrangeReport.positions() };
  }, t);
  assert.equal(shown.time, t, 'seek(t) does not show time t');
  assert.equal(shown.positions.length, data.points.length, 'positions() has not one entry per point');
  shown.positions.forEach((p, i) => {
    const point = data.points[i];
    assert.equal(p.name, point.name);
    assert.equal(p.x, point.x[row], `${point.name}: x at row ${row}`);
    assert.equal(p.y, point.y[row], `${point.name}: y at row ${row}`);
    assert.equal(p.z, data.dimension === 3 ? point.z[row] : null, `${point.name}: z at row ${row}`);
  });

  const next = row + 1;
  if (next < data.time.length && data.time[next] > t) {
    const middle = await page.evaluate((t) => {
      window.lagrangeReport.seek(t);
      return window.lagrangeReport.positions();
    }, (t + data.time[next]) / 2);
    middle.forEach((p, i) => {
      const point = data.points[i];
      for (const axis of data.dimension === 3 ? ['x', 'y', 'z'] : ['x', 'y']) {
        const expected = (point[axis][row] + point[axis][next]) / 2;
        assert.ok(Math.abs(p[axis] - expected) <= 1e-9 * (1 + Math.abs(expected)),
          `${point.name}: ${axis} half-way between rows ${row} and ${next} is ${p[axis]}, not ${expected}`);
      }
    });
  }
  return { time: t, row, positions: shown.positions };
}

/** Uses the page as a person would, so that those paths run too: hover, unwrap, drag, controls. */
async function exercisePage(page, data) {
  const plot = page.locator('.plot canvas').first();
  if (await plot.count()) {
    await plot.scrollIntoViewIfNeeded();
    const box = await plot.boundingBox();
    await page.mouse.move(box.x + box.width * 0.6, box.y + box.height * 0.5);
    assert.equal(await page.locator('#tooltip').isHidden(), false, 'hovering a plot shows no readout');
    await page.mouse.move(0, 0);
  }
  const unwrap = page.locator('#unwrap');
  if (await unwrap.isVisible()) {
    await unwrap.check();
    await unwrap.uncheck();
  }
  if (data.dimension === 3) {
    const stage = page.locator('#mechanism');
    await stage.scrollIntoViewIfNeeded();
    const box = await stage.boundingBox();
    await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
    await page.mouse.down();
    await page.mouse.move(box.x + box.width / 2 + 60, box.y + box.height / 2 + 20, { steps: 4 });
    await page.mouse.up();
  }
  await page.selectOption('#speed', '4');
  await page.locator('#loop').uncheck();
  await page.evaluate(() => window.scrollTo(0, 0));
}
