// The page in Debian's chromium, headless, driven by playwright-core (no browser download):
//   node e2e/page_test.mjs LOGIN_URL SCREENSHOT_PNG [HOLD_S]
// Run inside the slave's network namespace by tests/interop/test_web_page.py, which drives
// the master (pysoem) meanwhile and reads the progress lines printed here ("STEP ...").
// Steps: log in through the printed URL; see the default rack's RIMs and slots; see the
// loopback input (module 2, wired to the DO card the master writes) change; click
// "unplug RIM 2" and see the LEDs, RIM state and exception tree follow; screenshot.
import { chromium } from "playwright-core";

const [loginUrl, screenshot, holdArg] = process.argv.slice(2);
const holdSeconds = Number(holdArg ?? "0");  // stay open and streaming this long before the unplug
if (!loginUrl || !screenshot) {
  console.error("usage: node e2e/page_test.mjs LOGIN_URL SCREENSHOT_PNG");
  process.exit(2);
}
const step = (text) => console.log(`STEP ${text}`);
const fail = (text) => {
  throw new Error(text);
};

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"],
});
try {
  const page = await browser.newPage({ viewport: { width: 1600, height: 1400 } });
  const errors = [];
  page.on("pageerror", (e) => errors.push(String(e)));

  // Login: the URL sets the cookie and redirects to the page.
  const response = await page.goto(loginUrl);
  if (!response || response.url().includes("token=")) fail(`login did not redirect: ${response?.url()}`);
  const cookies = await page.context().cookies();
  const session = cookies.find((c) => c.name === "rackcat_session");
  if (!session || !session.httpOnly || session.sameSite !== "Strict") {
    fail(`session cookie not HttpOnly/SameSite=Strict: ${JSON.stringify(session)}`);
  }
  step("logged in");

  // The default rack: RIM 1 with slots 1..19, RIM 2 with slots 1..8 (docs/MDP.md).
  await page.locator('[data-testid="rim-2"]').waitFor({ timeout: 10000 });
  const rim1 = await page.locator('[data-testid="rim-1"] .slot').count();
  const rim2 = await page.locator('[data-testid="rim-2"] .slot').count();
  if (rim1 !== 19 || rim2 !== 8) fail(`slots: RIM 1 ${rim1}, RIM 2 ${rim2}`);
  const card = await page.locator('[data-testid="slot-1-1"] .card').textContent();
  step(`rack RIM 1 ${rim1} slots, RIM 2 ${rim2} slots, slot 1.1 ${card}`);
  for (const id of ["s0-rimpower-2", "s0-rimport-2", "s0-cmport-2"]) {
    await page.waitForFunction((i) => document.getElementById(i)?.className === "led green", id, { timeout: 10000 });
  }

  // Updates per second over the stream.
  await page.waitForFunction(() => parseInt(document.getElementById("rate")?.textContent ?? "0") >= 10, null, { timeout: 10000 });
  step(`stream ${await page.locator("#rate").textContent()}`);

  // The loopback input follows what the master writes to the DO card.
  const value = page.locator("#v-0-2-in-0");
  const seen = new Set();
  const until = Date.now() + 10000;
  while (seen.size < 2 && Date.now() < until) {
    seen.add(await value.textContent());
    await page.waitForTimeout(50);
  }
  if (seen.size < 2) fail(`module 2 input 0 did not change: ${[...seen]}`);
  step(`channel changed: ${[...seen].join(" -> ")}`);
  await page.locator("#v-0-2-in-0").click();  // plot it
  await page.waitForTimeout(1500);
  if (holdSeconds > 0) {
    step(`holding ${holdSeconds} s`);
    await page.waitForTimeout(holdSeconds * 1000);
  }

  // Unplug RIM 2 with a click: the API's answer shows, the LEDs go off, the tree updates.
  await page.getByRole("button", { name: "unplug RIM 2" }).click();
  await page.waitForFunction(() => (document.getElementById("result")?.textContent ?? "").includes("/rim/unplug -> 200"), null, { timeout: 10000 });
  step("unplugged");
  await page.waitForFunction(() => document.getElementById("s0-rimpower-2")?.className === "led off", null, { timeout: 10000 });
  await page.waitForFunction(() => (document.getElementById("s0-rimstate-2")?.textContent ?? "").startsWith("offline"), null, { timeout: 10000 });
  await page.waitForFunction(() => {
    const row = document.querySelector('[data-testid="exc-rim-2"]');
    return row !== null && (row.textContent ?? "").includes("offline") && (row.textContent ?? "").includes("bits 3");
  }, null, { timeout: 10000 });
  step("exception tree shows RIM 2 offline, bit 3 latched");
  await page.waitForFunction(() => document.querySelectorAll("#diagnosis-table tbody tr").length > 0, null, { timeout: 10000 });
  step("diagnosis history has a message");
  await page.screenshot({ path: screenshot, fullPage: true });
  step(`screenshot ${screenshot}`);
  if (errors.length) fail(`page errors: ${errors.join("; ")}`);
  step("done");
} finally {
  await browser.close();
}
