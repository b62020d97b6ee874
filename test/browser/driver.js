// Drive Debian chromium (headless) for the viewer tests, one JSON command per stdin line.
//
// Every command gets one JSON reply line on stdout: {"ok": true, ...} or {"ok": false, "error"}.
// Commands: open {url}, canvas, mouse {action: down|up|move, x, y, steps}, text,
// screenshot {path}, select {label, option}, check {label}, click {name} (a button),
// sent (the binary websocket frames the page sent since the last call, base64), close.
'use strict';

const fs = require('fs');
const readline = require('readline');
const { chromium } = require('playwright-core');

const CHROMIUM_FLAGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--no-first-run',
  '--enable-unsafe-swiftshader',
];

async function main() {
  const userDataDir = process.argv[2];
  const executablePath = process.env.CHROMIUM || '/usr/bin/chromium';
  const context = await chromium.launchPersistentContext(userDataDir, {
    executablePath,
    headless: true,
    args: CHROMIUM_FLAGS,
    viewport: { width: 960, height: 640 },
  });
  const page = context.pages()[0] || await context.newPage();
  // What the page tells the viewer (its camera among others), read by the tests in Python.
  const sentFrames = [];
  page.on('websocket', (ws) => {
    ws.on('framesent', (frame) => {
      if (typeof frame.payload !== 'string') {
        sentFrames.push(frame.payload.toString('base64'));
        if (sentFrames.length > 5000) sentFrames.shift();
      }
    });
  });
  const reply = (obj) => process.stdout.write(JSON.stringify(obj) + '\n');

  const handlers = {
    async open(cmd) {
      await page.goto(cmd.url, { waitUntil: 'load', timeout: 200000 });
      await page.waitForSelector('canvas', { timeout: 200000 });
      return {};
    },
    async canvas() {
      // The 3D view is the largest canvas on the page.
      const box = await page.evaluate(() => {
        let best = null;
        for (const canvas of document.querySelectorAll('canvas')) {
          const r = canvas.getBoundingClientRect();
          if (!best || r.width * r.height > best.width * best.height) {
            best = { x: r.x, y: r.y, width: r.width, height: r.height };
          }
        }
        return best;
      });
      if (!box) throw new Error('no canvas on the page');
      return { box };
    },
    async mouse(cmd) {
      if (cmd.action === 'move') {
        await page.mouse.move(cmd.x, cmd.y, { steps: cmd.steps || 1 });
      } else if (cmd.action === 'down') {
        await page.mouse.move(cmd.x, cmd.y);
        await page.mouse.down();
      } else if (cmd.action === 'up') {
        await page.mouse.up();
      } else {
        throw new Error(`unknown mouse action ${cmd.action}`);
      }
      return {};
    },
    async text() {
      return { text: await page.evaluate(() => document.body.innerText) };
    },
    async screenshot(cmd) {
      // Straight from the DevTools protocol: page.screenshot() waits for fonts and a quiet
      // frame, which a continuously rendering WebGL page on a software rasteriser may not give.
      const session = await context.newCDPSession(page);
      try {
        const shot = await session.send('Page.captureScreenshot', { format: 'png' });
        fs.writeFileSync(cmd.path, Buffer.from(shot.data, 'base64'));
      } finally {
        await session.detach();
      }
      return {};
    },
    async select(cmd) {
      // Mantine searchable select: click the input labelled cmd.label, type, pick the option.
      const input = page.getByLabel(cmd.label, { exact: true }).first();
      await input.click();
      await input.fill(cmd.option);
      await page.getByRole('option', { name: cmd.option, exact: true }).click();
      return {};
    },
    async click(cmd) {
      await page.getByRole('button', { name: cmd.name, exact: true }).first().click();
      return {};
    },
    async sent() {
      return { frames: sentFrames.splice(0, sentFrames.length) };
    },
    async check(cmd) {
      await page.getByLabel(cmd.label, { exact: true }).first().click();
      return {};
    },
  };

  const lines = readline.createInterface({ input: process.stdin });
  for await (const line of lines) {
    if (!line.trim()) continue;
    let cmd;
    try {
      cmd = JSON.parse(line);
    } catch (error) {
      reply({ ok: false, error: `bad JSON: ${line}` });
      continue;
    }
    if (cmd.cmd === 'close') break;
    const handler = handlers[cmd.cmd];
    if (!handler) {
      reply({ ok: false, error: `unknown command ${cmd.cmd}` });
      continue;
    }
    try {
      reply({ ok: true, ...(await handler(cmd)) });
    } catch (error) {
      reply({ ok: false, error: String(error && error.message ? error.message : error) });
    }
  }
  await context.close();
  reply({ ok: true, closed: true });
}

main().catch((error) => {
  process.stderr.write(String(error && error.stack ? error.stack : error) + '\n');
  process.exit(1);
});
