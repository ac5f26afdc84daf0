// The page of render_client --web in a real browser: headless Debian chromium driven by
// puppeteer-core (tests/web/node_modules, scripts/setup.sh). A cluster started by
// scripts/cluster.sh --web serves a small city; the test checks that
//   - a wrong or missing token gets 403 and not the page;
//   - a bad HTTP request, an oversized and a malformed WebSocket message each close only their
//     connection, with a log line, and the frames go on;
//   - a mouse drag on the drive page moves the camera and JPEG frames arrive, with a latency; a
//     held key and a touch drag move it too;
//   - once the camera is still a PNG arrives that equals, pixel for pixel (frame_diff), what
//     the reference renderer renders for the camera the page reports;
//   - the view-only page gets the frames but its drag moves nothing;
//   - the stop button ends the cluster, every process with status 0;
//   - the reference renderer serves the page over https/wss with --web 0,tls=self-signed.
// Usage: node browser_test.js SOURCE_DIR BIN_DIR. Exit 0 pass, 1 fail, 77 skipped (no chromium).
"use strict";
const fs = require("fs");
const net = require("net");
const os = require("os");
const path = require("path");
const { spawn, spawnSync } = require("child_process");

const [src, bin] = process.argv.slice(2);
const CHROMIUM = "/usr/bin/chromium";
const SCENE = "city:4x4:2:6:1";
const VIEW = ["--width", "128", "--height", "96"];

if (!fs.existsSync(CHROMIUM)) {
  console.log("SKIP: " + CHROMIUM + " is not installed (Debian package chromium, scripts/setup.sh)");
  process.exit(77);
}
let puppeteer;
try {
  puppeteer = require(path.join(src, "tests/web/node_modules/puppeteer-core"));
} catch (e) {
  console.error("FAIL: puppeteer-core is not in tests/web/node_modules: run scripts/setup.sh (" + e.message + ")");
  process.exit(1);
}

const tmp = fs.mkdtempSync(path.join(os.tmpdir(), "occ_web_test."));
const out = path.join(tmp, "run");
const log = path.join(out, "render_client.log");
let cluster = null, browser = null, clusterExit = null;

function check(ok, what) {
  if (!ok) throw new Error(what);
  console.log("ok: " + what);
}
const sleep = ms => new Promise(r => setTimeout(r, ms));
async function until(what, fn, ms = 60000) {
  const end = Date.now() + ms;
  for (;;) {
    const v = await fn();
    if (v) return v;
    if (clusterExit !== null) throw new Error(what + ": the cluster exited (" + clusterExit + ")");
    if (Date.now() > end) throw new Error("timed out waiting for " + what);
    await sleep(100);
  }
}
const readLog = () => (fs.existsSync(log) ? fs.readFileSync(log, "utf8") : "");
const occ = page => page.evaluate(() => ({ role: occ.role, frames: occ.frames, stills: occ.stills, sent: occ.sent,
                                           last: occ.last, latencies: occ.latencies, closed: occ.closed }));

async function drag(page, dx) {
  const box = await (await page.$("#view")).boundingBox();
  const x = box.x + box.width / 2, y = box.y + box.height / 2;
  await page.mouse.move(x, y);
  await page.mouse.down();
  for (let i = 1; i <= 8; ++i) {
    await page.mouse.move(x + (dx * i) / 8, y);
    await sleep(30);
  }
  await page.mouse.up();
}

// A raw HTTP request that is not HTTP: the server closes the connection.
function badHttp(port) {
  return new Promise((resolve, reject) => {
    const s = net.connect(port, "127.0.0.1", () => s.write("GARBAGE\x01 / HTTP/9\r\n\r\n"));
    s.on("data", () => {});
    s.on("close", () => resolve(true));
    s.on("error", () => resolve(true));
    setTimeout(() => reject(new Error("a bad HTTP request left its connection open")), 15000);
  });
}

// A WebSocket with the drive token that sends `msg`: the close code it gets.
function wsClose(page, wsUrl, msg) {
  return page.evaluate((u, m) => new Promise(resolve => {
    const ws = new WebSocket(u);
    ws.onopen = () => ws.send(m);
    ws.onclose = ev => resolve(ev.code);
    setTimeout(() => resolve(-1), 15000);
  }), wsUrl, msg);
}

async function main() {
  cluster = spawn("/bin/bash", [path.join(src, "scripts/cluster.sh"), "--scene", SCENE, "--web", "0", "--out", out,
                                "--images", "off", "--timeout-ms", "20000", ...VIEW],
                  { env: { ...process.env, OCC_BIN: bin }, detached: true, stdio: ["ignore", "inherit", "inherit"] });
  cluster.on("exit", (code, sig) => { clusterExit = sig || code; });
  const drive = await until("the drive URL in render_client.log", () => (readLog().match(/\(drive\): (\S+)/) || [])[1], 180000);
  const view = readLog().match(/\(view only\): (\S+)/)[1];
  const base = drive.split("?")[0], port = Number(new URL(drive).port);
  const wsDrive = "ws://127.0.0.1:" + port + "/ws?token=" + new URL(drive).searchParams.get("token");

  browser = await puppeteer.launch({ executablePath: CHROMIUM, headless: true,
                                     args: ["--no-sandbox", "--disable-gpu", "--window-size=400,300"] });
  const page = await browser.newPage();
  await page.setViewport({ width: 400, height: 300, hasTouch: true });

  // No token, a wrong one: 403 and not the page.
  for (const u of [base, base + "?token=0123456789abcdef0123456789abcdef"]) {
    const r = await page.goto(u);
    const body = await page.content();
    check(r.status() === 403 && !body.includes("<canvas"), "403 without the page for " + u.replace(/token=.*/, "token=wrong"));
  }

  const r = await page.goto(drive);
  check(r.status() === 200, "the drive URL serves the page");
  await until("the first frames on the drive page", async () => (await occ(page)).frames >= 1);
  check((await occ(page)).role === "drive", "the drive page is told it drives");

  // Bad input closes its own connection only.
  await badHttp(port);
  check(await wsClose(page, wsDrive, "1 kd w ".repeat(20)) === 1009, "an oversized WebSocket message is closed (1009)");
  check(await wsClose(page, wsDrive, "1 jump") === 1008, "a malformed input message is closed (1008)");
  const l = readLog();
  check(/bad HTTP request/.test(l) && /input message longer than 64 bytes: WebSocket closed/.test(l) && /input kind 'jump'/.test(l),
        "each bad request has its log line");

  // A drag moves the camera; JPEG frames with a latency; then the still PNG.
  const before = await until("a still frame before the drag", async () => { const o = await occ(page); return o.stills >= 1 && o; });
  await drag(page, 60);
  const moved = await until("the camera to move", async () => {
    const o = await occ(page);
    return o.last.camera !== before.last.camera && o.frames > before.frames && o.latencies.length > 0 && o;
  });
  check((await occ(page)).closed === null, "the drive page stays connected after the bad connections");
  check(moved.latencies.every(x => x > 0), "the page measures the input-to-frame latency (" + moved.latencies.map(Math.round).join(", ") + " ms)");

  // A held key and a touch drag steer too.
  const moves = async (what, act) => {  // from a still frame, so nothing else is moving it
    const c0 = (await until("a still frame", async () => { const o = await occ(page); return o.last.format === "png" && o; })).last.camera;
    await act();
    await until(what + " to move the camera", async () => (await occ(page)).last.camera !== c0);
    console.log("ok: " + what + " moves the camera");
  };
  await moves("a held W key", async () => { await page.keyboard.down("w"); await sleep(300); await page.keyboard.up("w"); });
  await moves("a touch drag", async () => {
    const box = await (await page.$("#view")).boundingBox();
    const x = box.x + box.width / 2, y = box.y + box.height / 2;
    await page.touchscreen.touchStart(x, y);
    for (let i = 1; i <= 6; ++i) { await page.touchscreen.touchMove(x, y + 5 * i); await sleep(30); }
    await page.touchscreen.touchEnd();
  });
  const still = await until("the still frame after the drag", () => page.evaluate(n => {
    const s = occ.lastStill;
    if (!s || s.header.frame <= n || occ.last !== s.header) return null;
    let b = "";
    for (const c of s.image) b += String.fromCharCode(c);
    return { camera: s.header.camera, png: btoa(b), frames: occ.frames };
  }, before.last.frame));
  check(still.camera !== before.last.camera, "the still frame has the moved camera");

  // The view-only page watches but cannot steer.
  const vpage = await browser.newPage();
  check((await vpage.goto(view)).status() === 200, "the view-only URL serves the page");
  await until("the view-only page's first frame", async () => (await occ(vpage)).frames >= 1);
  check((await occ(vpage)).role === "view", "the view-only page is told it only watches");
  await drag(vpage, 80);
  await until("the view page to send its drag", async () => (await occ(vpage)).sent >= 3);
  await sleep(3000);
  const after = await occ(page);
  check(after.last.camera === still.camera && after.frames === still.frames, "a view-only drag moves nothing");

  // Stop: the cluster ends, every process with status 0.
  await page.bringToFront();
  await page.evaluate(() => document.getElementById("stop").click());
  await until("the cluster to exit", () => clusterExit !== null || null, 60000).catch(() => {});
  check(clusterExit === 0, "the stop button ends the cluster with status 0 (" + clusterExit + ")");
  await browser.close();
  browser = null;

  // The still frame equals the reference renderer's frame for its camera.
  const header = "frame,eye_x,eye_y,eye_z,target_x,target_y,target_z,up_x,up_y,up_z,fovy_deg,near,far\n";
  fs.writeFileSync(path.join(tmp, "camera.csv"), header + "0," + still.camera + "\n");
  fs.mkdirSync(path.join(tmp, "web"));
  fs.writeFileSync(path.join(tmp, "web/frame_00000.png"), Buffer.from(still.png, "base64"));
  const ref = spawnSync(path.join(bin, "render_client"), ["--scene", SCENE, ...VIEW, "--path",
                        path.join(tmp, "camera.csv"), "--out", path.join(tmp, "ref")], { encoding: "utf8" });
  check(ref.status === 0, "the reference renders the camera the page reported" + (ref.status ? ": " + ref.stderr : ""));
  const diff = spawnSync(path.join(bin, "frame_diff"), [path.join(tmp, "ref"), path.join(tmp, "web")], { encoding: "utf8" });
  check(diff.status === 0 && /frames=1 differing_pixels=0 /.test(diff.stdout),
        "the still frame equals the reference pixel for pixel (" + diff.stdout.trim().split("\n").pop() + ")");
  await overTls();
}

// The reference renderer with --web 0,tls=self-signed: the page and its frames over https/wss.
async function overTls() {
  cluster = null;
  clusterExit = null;  // until() watches the cluster: it has ended
  let err = "";
  const ref = spawn(path.join(bin, "render_client"), ["--scene", SCENE, ...VIEW, "--web",
                    "0,tls=self-signed"], { stdio: ["ignore", "ignore", "pipe"] });
  ref.stderr.on("data", d => { err += d; });
  let status = null;
  ref.on("exit", c => { status = c; });
  try {
    const url = await until("the https URL", () => (err.match(/\(drive\): (https:\S+)/) || [])[1], 120000);
    check(/self-signed certificate for localhost, SHA-256 [0-9A-F:]{95}/.test(err), "the certificate's fingerprint is printed");
    browser = await puppeteer.launch({ executablePath: CHROMIUM, headless: true, acceptInsecureCerts: true,
                                       args: ["--no-sandbox", "--disable-gpu"] });
    const page = await browser.newPage();
    check((await page.goto(url)).status() === 200, "the page over https");
    await until("a still frame over wss", async () => (await occ(page)).stills >= 1);
    await page.evaluate(() => document.getElementById("stop").click());
    await until("the reference renderer to exit", () => status !== null, 60000);
    check(status === 0, "the stop button ends the reference renderer with status 0 (" + status + ")");
  } finally {
    if (status === null) ref.kill();
  }
}

main().then(() => {
  fs.rmSync(tmp, { recursive: true, force: true });
  console.log("PASS");
  process.exit(0);
}).catch(async e => {
  console.error("FAIL: " + e.message + "\n--- render_client.log (" + tmp + " kept) ---\n" + readLog().slice(-4000));
  if (browser) await browser.close().catch(() => {});
  if (cluster && clusterExit === null) try { process.kill(-cluster.pid, "SIGTERM"); } catch (err) {}
  process.exit(1);
});
