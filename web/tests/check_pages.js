#!/usr/bin/env node
// Opens tdf's HTML reports in headless Chromium from file:// and checks what a person would see:
//   - no console error, no uncaught exception, no failed request;
//   - every <img> loaded (complete, naturalWidth > 0);
//   - every sortable table sorts its numeric columns on a click; every loss plot is drawn;
//   - every 3D view reaches data-state="ready", and a screenshot of its canvas has model pixels
//     where tdf's own renderer sees the model from the same camera (`tdf render`, mask pass):
//     intersection over union of the two silhouettes >= --min-iou.
// Writes a full-page screenshot of each page and of each 3D view to --out.
//
//   node check_pages.js --chromium /usr/bin/chromium --tdf build/tdf --out DIR [--min-iou 0.97] PAGE.html...
// Prints one line per check and "N passed, M failed"; exit 0 only when everything passed.
'use strict';

const fs = require('fs');
const path = require('path');
const os = require('os');
const {execFileSync} = require('child_process');
const {pathToFileURL} = require('url');
const puppeteer = require('puppeteer-core');
const {PNG} = require('pngjs');

function parseArgs(argv) {
  const o = {chromium: '/usr/bin/chromium', tdf: '', out: path.join(os.tmpdir(), 'tdf_pages'), minIou: 0.97, pages: []};
  for (let i = 0; i < argv.length; ++i) {
    const a = argv[i];
    if (a === '--chromium') o.chromium = argv[++i];
    else if (a === '--tdf') o.tdf = argv[++i];
    else if (a === '--out') o.out = argv[++i];
    else if (a === '--min-iou') o.minIou = Number(argv[++i]);
    else o.pages.push(a);
  }
  if (!o.pages.length) throw new Error('usage: check_pages.js [--chromium PATH] [--tdf PATH] [--out DIR] PAGE.html...');
  return o;
}

let passed = 0;
let failed = 0;
function check(ok, name, detail) {
  if (ok) ++passed;
  else ++failed;
  console.log(`${ok ? 'PASS' : 'FAIL'} ${name}${detail ? ': ' + detail : ''}`);
}

function parseHex(hex) {
  const v = parseInt(hex.replace('#', ''), 16);
  return [(v >> 16) & 255, (v >> 8) & 255, v & 255];
}

// Our renderer's silhouette at the viewer's start camera: `tdf render` of the same .glb, mask pass.
function rendererMask(tdf, glbPath, camera, width, height, workDir) {
  fs.mkdirSync(workDir, {recursive: true});
  const scene = {
    mesh: glbPath,
    image: {width, height},
    passes: ['mask'],
    views: {target: camera.target, fovy: camera.fovy,
            orbit: [{elevation: camera.orbit.elevation, azimuth: camera.orbit.azimuth, radius: camera.orbit.radius}]},
  };
  const scenePath = path.join(workDir, 'silhouette_scene.json');
  fs.writeFileSync(scenePath, JSON.stringify(scene, null, 2));
  execFileSync(tdf, ['--quiet', 'render', scenePath, '-o', workDir, '--png'], {stdio: ['ignore', 'ignore', 'inherit']});
  const png = PNG.sync.read(fs.readFileSync(path.join(workDir, 'view_000_mask.png')));
  const mask = new Uint8Array(width * height);
  for (let i = 0; i < width * height; ++i) mask[i] = png.data[4 * i] > 127 ? 1 : 0;
  return mask;
}

async function checkViewer(page, handle, index, pagePath, o, shotBase) {
  const name = `${path.basename(pagePath)} viewer ${index}`;
  const state = await page
    .waitForFunction((el) => ['ready', 'error', 'unavailable'].includes(el.getAttribute('data-state')),
                     {timeout: 120000}, handle)
    .then(() => handle.evaluate((el) => el.getAttribute('data-state')))
    .catch(() => 'timeout');
  const status = await handle.evaluate((el) => {
    const s = el.querySelector('.tdf-viewer-status');
    return s ? s.textContent : '';
  });
  check(state === 'ready', `${name} loads the model`, `state ${state} (${status})`);
  if (state !== 'ready') return;
  const canvas = await handle.$('canvas');
  await canvas.screenshot({path: `${shotBase}_viewer${index}.png`});
  // Measure on a magenta background (the page's background control): no shading of a model comes
  // near it, so dark, shadowed parts still count as model.
  const camera = JSON.parse(await handle.evaluate((el) => el.getAttribute('data-camera')));
  const setBackground = (hex) => handle.evaluate((el, value) => {
    const input = el.querySelector('[data-control=background]');
    input.value = value;
    input.dispatchEvent(new Event('input'));
  }, hex);
  await setBackground('#ff00ff');
  const background = [255, 0, 255];
  const shotPath = `${shotBase}_viewer${index}_silhouette.png`;
  await canvas.screenshot({path: shotPath});
  const shot = PNG.sync.read(fs.readFileSync(shotPath));
  const model = new Uint8Array(shot.width * shot.height);
  let modelPixels = 0;
  for (let i = 0; i < shot.width * shot.height; ++i) {
    const d = Math.max(Math.abs(shot.data[4 * i] - background[0]), Math.abs(shot.data[4 * i + 1] - background[1]),
                       Math.abs(shot.data[4 * i + 2] - background[2]));
    model[i] = d > 40 ? 1 : 0;
    modelPixels += model[i];
  }
  check(modelPixels > 0.01 * shot.width * shot.height, `${name} shows the model`,
        `${modelPixels} of ${shot.width * shot.height} pixels differ from the background`);
  await checkInteraction(page, handle, canvas, name, background, modelPixels);
  await setBackground(camera.background || '#30343a');
  if (!o.tdf) return;
  const glb = await handle.evaluate((el) => {
    const a = el.querySelector('a[href$=".glb"]');
    return a ? a.getAttribute('href') : '';
  });
  const glbPath = path.resolve(path.dirname(pagePath), decodeURIComponent(glb));
  const reference = rendererMask(o.tdf, glbPath, camera, shot.width, shot.height, `${shotBase}_viewer${index}_render`);
  let inter = 0;
  let union = 0;
  for (let i = 0; i < model.length; ++i) {
    inter += model[i] & reference[i];
    union += model[i] | reference[i];
  }
  const iou = union ? inter / union : 0;
  check(iou >= o.minIou, `${name} silhouette matches tdf render`, `IoU ${iou.toFixed(4)} (min ${o.minIou})`);
}

// The controls a person uses: the wheel zooms (the model covers more pixels), the light sliders
// change the shading. Restores the start view afterwards (reset button).
async function checkInteraction(page, handle, canvas, name, background, modelPixelsBefore) {
  const grab = async () => PNG.sync.read(Buffer.from(await canvas.screenshot()));
  const countModel = (png) => {
    let n = 0;
    for (let i = 0; i < png.width * png.height; ++i) {
      const d = Math.max(Math.abs(png.data[4 * i] - background[0]), Math.abs(png.data[4 * i + 1] - background[1]),
                         Math.abs(png.data[4 * i + 2] - background[2]));
      if (d > 40) ++n;
    }
    return n;
  };
  const box = await canvas.boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.wheel({deltaY: -400});
  await page.evaluate(() => new Promise((resolve) => requestAnimationFrame(() => resolve())));
  const zoomed = countModel(await grab());
  check(zoomed > modelPixelsBefore, `${name} wheel zooms in`, `${modelPixelsBefore} -> ${zoomed} model pixels`);
  const before = await grab();
  await handle.evaluate((el) => {
    const slider = el.querySelector('[data-control=light-azimuth]');
    slider.value = String(-Number(slider.value) - 60);
    slider.dispatchEvent(new Event('input'));
  });
  const after = await grab();
  let changed = 0;
  for (let i = 0; i < before.data.length; i += 4) if (Math.abs(before.data[i] - after.data[i]) > 8) ++changed;
  check(changed > 0.01 * before.width * before.height, `${name} light slider moves the light`, `${changed} pixels changed`);
  await handle.evaluate((el) => {
    const slider = el.querySelector('[data-control=light-azimuth]');
    slider.value = '35';
    slider.dispatchEvent(new Event('input'));
    el.querySelector('[data-control=reset]').click();
  });
}

// Loss plots: drawn (data-state ready) with coloured curve pixels on the white canvas.
async function checkPlots(page, pageName, shotBase) {
  const plots = await page.$$('.tdf-plot');
  for (let p = 0; p < plots.length; ++p) {
    const state = await plots[p].evaluate((el) => el.getAttribute('data-state'));
    const canvas = await plots[p].$('canvas');
    const shotPath = `${shotBase}_plot${p}.png`;
    await canvas.screenshot({path: shotPath});
    const png = PNG.sync.read(fs.readFileSync(shotPath));
    let coloured = 0;
    for (let i = 0; i < png.width * png.height; ++i) {
      const r = png.data[4 * i], g = png.data[4 * i + 1], b = png.data[4 * i + 2];
      if (Math.max(r, g, b) - Math.min(r, g, b) > 60) ++coloured;
    }
    check(state === 'ready' && coloured > 200, `${pageName} loss plot ${p} is drawn`, `state ${state}, ${coloured} curve pixels`);
  }
}

async function checkSortable(page, pageName) {
  const tables = await page.$$('table.sortable');
  for (let t = 0; t < tables.length; ++t) {
    const headers = await tables[t].$$('thead th');
    for (let c = 0; c < headers.length; ++c) {
      const type = await headers[c].evaluate((th) => th.getAttribute('data-type'));
      if (type !== 'number') continue;
      const label = await headers[c].evaluate((th) => th.textContent);
      for (const direction of ['asc', 'desc']) {
        await headers[c].click();
        const values = await tables[t].evaluate((table, column) => Array.prototype.map.call(table.tBodies[0].rows,
          (row) => row.cells[column].getAttribute('data-value')), c);
        const numbers = values.filter((v) => v !== '' && v !== null).map(Number);
        const blanksLast = values.slice(numbers.length).every((v) => v === '' || v === null);
        let sorted = true;
        for (let i = 1; i < numbers.length; ++i)
          if (direction === 'asc' ? numbers[i] < numbers[i - 1] : numbers[i] > numbers[i - 1]) sorted = false;
        check(sorted && blanksLast, `${pageName} sorts by "${label}" ${direction}`, values.join(' '));
      }
    }
  }
}

async function main() {
  const o = parseArgs(process.argv.slice(2));
  fs.mkdirSync(o.out, {recursive: true});
  const browser = await puppeteer.launch({
    executablePath: o.chromium,
    headless: true,
    // --no-sandbox: CI runs as root. SwiftShader: WebGL without a GPU (headless Chromium no longer
    // falls back to it by itself). Nothing here loosens file:// rules: the pages must work as a
    // user's browser opens them.
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-gpu-sandbox'],
    defaultViewport: {width: 1400, height: 1000, deviceScaleFactor: 1},
  });
  const pid = browser.process() ? browser.process().pid : 0;
  console.log(`chromium ${await browser.version()} pid ${pid}`);
  try {
    for (const pageArg of o.pages) {
      const pagePath = path.resolve(pageArg);
      const name = path.basename(pagePath);
      const shotBase = path.join(o.out, name.replace(/\.html$/, ''));
      const page = await browser.newPage();
      const problems = [];
      page.on('console', (msg) => {
        if (msg.type() === 'error') problems.push(`console error: ${msg.text()}`);
      });
      page.on('pageerror', (err) => problems.push(`uncaught: ${err.message}`));
      page.on('requestfailed', (req) => problems.push(`request failed: ${req.url()} ${req.failure().errorText}`));
      await page.goto(pathToFileURL(pagePath).href, {waitUntil: 'load', timeout: 120000});
      const broken = await page.evaluate(() => Array.prototype.filter.call(document.images,
        (img) => !img.complete || img.naturalWidth === 0).map((img) => img.getAttribute('src')));
      const count = await page.evaluate(() => document.images.length);
      check(broken.length === 0, `${name} loads every image`, `${count - broken.length} of ${count}` +
            (broken.length ? `; broken: ${broken.slice(0, 5).join(', ')}` : ''));
      const viewers = await page.$$('.tdf-viewer');
      for (let v = 0; v < viewers.length; ++v) await checkViewer(page, viewers[v], v, pagePath, o, shotBase);
      await checkSortable(page, name);
      await checkPlots(page, name, shotBase);
      await page.screenshot({path: `${shotBase}_page.png`, fullPage: true});
      check(problems.length === 0, `${name} has no console errors`, problems.slice(0, 5).join(' | '));
      await page.close();
    }
  } finally {
    await browser.close();
    // Make sure the browser we started is gone (by its PID, nothing else).
    if (pid) {
      try {
        process.kill(pid, 0);
        process.kill(pid, 'SIGKILL');
      } catch (e) { /* already exited */ }
    }
  }
  console.log(`${passed} passed, ${failed} failed`);
  process.exitCode = failed ? 1 : 0;
}

main().catch((err) => {
  console.error(err && err.stack ? err.stack : err);
  process.exitCode = 2;
});
