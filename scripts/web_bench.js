#!/usr/bin/env node
// What render_client --web costs and delivers, as the page sees it (docs/web.md): for each
// viewport and number of watchers, scripts/cluster.sh --web on a scene, one drive page and
// (watchers - 1) view-only pages in headless chromium (puppeteer-core from tests/web/node_modules,
// scripts/setup.sh). The drive page holds an arrow key for half of --seconds (the camera turns
// every frame), then drags the mouse for the other half (an event every 33 ms) and lets go; the
// table has, per run:
//   jpeg ms, png ms   encode time of a frame (median; the server's own clock, on the viewer's thread)
//   fps, kbit/s       frames a second each page drew and bits it received while the key turned the
//                     camera (mean of the pages)
//   latency ms        drag event (the page's clock) to the first frame whose camera includes it,
//                     drawn: median and p95 over the drive page's events
//   cluster fps       frames a second the cluster rendered while the key turned the camera (the
//                     frame numbers of the frames the drive page received)
//   shown             fps / cluster fps: the share of the cluster's frames each page showed
//   in render_client  of the latency, the part from the input's arrival at the render client to
//                     its frame encoded (median): the rest is the way there and back and the page
//   render ms         the cluster's own latency (its camera sent to the frame shown), median over
//                     the drag's frames, one frame interval, and the link's round trip as the page
//                     measures it ("SEQ ping" to its pong, median over the drag): the target is
//                     latency <= render ms + one frame + rtt
// No assertions: it prints the table and exits 0 (2 on a bad flag, 1 when a run fails).
//
//   scripts/web_bench.js [--scene S] [--sizes 1024x1024,1920x1080] [--watchers 1,4] [--seconds N]
//                        [--nice N] [--out DIR] [--screenshot FILE.png] [cluster.sh args ...]
// --nice N: the cluster runs at that niceness (0..19, default 0), so that a browser on the same
// cores gets the CPU when it needs it, as it would on a machine of its own.
"use strict";
const fs = require("fs");
const path = require("path");
const { spawn } = require("child_process");

const root = path.resolve(__dirname, "..");
const head = fs.readFileSync(__filename, "utf8").split("\n").slice(1);
const usage = head.slice(0, head.findIndex(l => !l.startsWith("//"))).map(l => l.replace(/^\/\/ ?/, "")).join("\n");
const opt = { scene: "city", sizes: "1024x1024,1920x1080", watchers: "1,4", seconds: "6", nice: "0", out: "out/web_bench", screenshot: "" };
const extra = [];
for (let a = process.argv.slice(2); a.length; ) {
  const f = a.shift();
  if (f === "--help" || f === "-h") { console.log(usage); process.exit(0); }
  if (f === "--version") {
    console.log("web_bench.js (occswitch) " + fs.readFileSync(path.join(root, "VERSION"), "utf8").trim());
    process.exit(0);
  }
  const k = f.replace(/^--/, "");
  if (f.startsWith("--") && k in opt) {
    if (!a.length) { console.error("error: " + f + " needs a value"); process.exit(2); }
    opt[k] = a.shift();
  } else {
    extra.push(f);
  }
}
const sizes = opt.sizes.split(",").map(s => s.split("x").map(Number));
const watchers = opt.watchers.split(",").map(Number);
if (sizes.some(s => s.length !== 2 || !(s[0] > 0 && s[1] > 0)) || watchers.some(n => !(n >= 1 && n <= 16)) ||
    !/^(1?[0-9])$/.test(opt.nice)) {
  console.error("error: --sizes WxH[,WxH...], --watchers N[,N...] (1..16) and --nice N (0..19)");
  process.exit(2);
}
const puppeteer = require(path.join(root, "tests/web/node_modules/puppeteer-core"));
const sleep = ms => new Promise(r => setTimeout(r, ms));
const median = v => (v.length ? [...v].sort((a, b) => a - b)[Math.floor(v.length / 2)] : NaN);
const p95 = v => (v.length ? [...v].sort((a, b) => a - b)[Math.min(v.length - 1, Math.floor(v.length * 0.95))] : NaN);

async function until(what, fn, ms) {
  for (const end = Date.now() + ms; Date.now() < end; await sleep(100)) {
    const v = await fn();
    if (v) return v;
  }
  throw new Error("timed out waiting for " + what);
}

// One run: the cluster, the pages, the drag, the still frame, the stop button.
async function run(browser, [w, h], n) {
  const out = path.join(opt.out, w + "x" + h + "_" + n);
  fs.rmSync(out, { recursive: true, force: true });
  const log = path.join(out, "render_client.log");
  const readLog = () => (fs.existsSync(log) ? fs.readFileSync(log, "utf8") : "");
  const cluster = spawn("nice", ["-n", opt.nice, "/bin/bash", path.join(root, "scripts/cluster.sh"), "--scene", opt.scene, "--web", "0",
                                      "--out", out, "--images", "off", "--width", String(w), "--height", String(h), ...extra],
                        { stdio: ["ignore", "ignore", "ignore"] });
  let exited = null;
  cluster.on("exit", c => { exited = c; });
  const drive = await until("the drive URL", () => exited === null && (readLog().match(/\(drive\): (\S+)/) || [])[1], 600000);
  const view = readLog().match(/\(view only\): (\S+)/)[1];
  const pages = [];
  for (let i = 0; i < n; ++i) {
    const p = await browser.newPage();
    await p.setViewport({ width: w, height: h + 48 });
    await p.goto(i === 0 ? drive : view);
    pages.push(p);
  }
  const page = pages[0];
  await page.bringToFront();
  await until("the first still frame", () => page.evaluate(() => occ.stills >= 1), 600000);
  const state = () => Promise.all(pages.map(p => p.evaluate(() => ({ frames: occ.drawn, bytes: occ.bytes,
                                                                       rendered: occ.last.frame }))));
  await page.evaluate(() => { occ.encode = { jpeg: [], png: [] }; occ.render = []; occ.server = []; const on = occ.ws.onmessage;
    occ.ws.onmessage = ev => { on(ev); if (typeof ev.data === "string") return;
      occ.encode[occ.last.format].push(occ.last.encode_ms); occ.render.push(occ.last.latency_ms);
      if (occ.last.input_ms >= 0) occ.server.push(occ.last.input_ms); }; });
  // A held arrow key turns the camera every frame the viewer takes: fps and kbit/s.
  await page.keyboard.down("ArrowLeft");
  await sleep(500);
  const s0 = await state(), t0 = Date.now();
  await sleep(opt.seconds * 500);
  const s1 = await state(), t1 = Date.now();
  await page.keyboard.up("ArrowLeft");
  // A drag, an event every 33 ms: the latency of each.
  const lat0 = await page.evaluate(() => occ.latencies.length), render0 = await page.evaluate(() => occ.render.length),
        server0 = await page.evaluate(() => occ.server.length),
        rtt0 = await page.evaluate(() => occ.rtts.length);
  await page.mouse.move(w / 2, h / 2);
  await page.mouse.down();
  for (let i = 0, t = Date.now(); Date.now() - t < opt.seconds * 500; ++i) {
    await page.mouse.move(w / 2 + 200 * Math.sin(i / 15), h / 2);
    await sleep(33);
  }
  const stills = await page.evaluate(() => occ.stills);
  await page.mouse.up();
  await until("the still frame after the drag", () => page.evaluate(k => occ.stills > k, stills), 120000);
  if (opt.screenshot && !fs.existsSync(opt.screenshot)) await page.screenshot({ path: opt.screenshot });
  const r = await page.evaluate((k, m, j, k0) => ({ latencies: occ.latencies.slice(k), encode: occ.encode,
                                                  render: occ.render.slice(m), server: occ.server.slice(j),
                                                  rtts: occ.rtts.slice(k0) }),
                                 lat0 + 1, render0, server0 + 1, rtt0);
  await page.evaluate(() => document.getElementById("stop").click());
  for (const p of pages) await p.close();
  await until("the cluster to exit", () => exited !== null, 120000);
  const secs = (t1 - t0) / 1000;
  const fps = s1.reduce((a, s, i) => a + (s.frames - s0[i].frames), 0) / n / secs;
  const rendered = (s1[0].rendered - s0[0].rendered) / secs;
  return { size: w + "x" + h, n, jpeg: median(r.encode.jpeg), png: median(r.encode.png), fps, cluster: rendered,
           kbit: s1.reduce((a, s, i) => a + (s.bytes - s0[i].bytes), 0) * 8 / 1000 / n / secs,
           lat: median(r.latencies), lat95: p95(r.latencies), render: median(r.render), server: median(r.server),
           rtt: median(r.rtts), status: exited };
}

async function main() {
  const browser = await puppeteer.launch({ executablePath: "/usr/bin/chromium", headless: true,
                                           args: ["--no-sandbox", "--disable-gpu"] });
  const rows = [];
  try {
    for (const s of sizes) for (const n of watchers) rows.push(await run(browser, s, n));
  } finally {
    await browser.close();
  }
  const f = (v, d) => (isNaN(v) ? "-" : v.toFixed(d));
  console.log("| viewport | watchers | jpeg ms | png ms | fps (each page) | cluster fps | shown | kbit/s (each page) | " +
              "latency ms median / p95 | in render_client | render ms + one frame + rtt |");
  console.log("|---|---|---|---|---|---|---|---|---|---|---|");
  for (const r of rows)
    console.log(`| ${r.size} | ${r.n} | ${f(r.jpeg, 1)} | ${f(r.png, 0)} | ${f(r.fps, 1)} | ${f(r.cluster, 1)} | ` +
                `${f(r.fps / r.cluster, 2)} | ${f(r.kbit, 0)} | ${f(r.lat, 0)} / ${f(r.lat95, 0)} | ${f(r.server, 0)} | ` +
                `${f(r.render, 0)} + ${f(1000 / r.cluster, 0)} + ${f(r.rtt, 0)} |`);
  if (rows.some(r => r.status !== 0)) throw new Error("a cluster exited with a status other than 0: see " + opt.out);
}

main().catch(e => { console.error("error: web_bench.js: " + e.message); process.exit(1); });
