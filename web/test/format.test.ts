import assert from "node:assert/strict";
import { test } from "node:test";
import { formatValue, hex, linkHealth, parseHex, setBits } from "../src/format";

test("engineering units", () => {
  assert.equal(formatValue(4, "V"), "4.000 V");
  assert.equal(formatValue(12.3456, "mA"), "12.346 mA");
  assert.equal(formatValue(21.44, "°C"), "21.4 °C");
  assert.equal(formatValue(1, "bit"), "1 bit");
  assert.equal(formatValue(1234, "counts"), "1234 counts");
  assert.equal(formatValue(150.04, "V"), "150.0 V");
  assert.equal(formatValue(null, "°C"), "open");
  assert.equal(formatValue(Number.NaN, "V"), "-");
});

test("register words", () => {
  assert.equal(hex(0x2021, 4), "0x2021");
  assert.equal(hex(-1, 8), "0xFFFFFFFF");
  assert.equal(parseHex("0x00000C04"), 0xc04);
  assert.equal(parseHex("0xFFFFFFFF"), 0xffffffff);
  assert.equal(parseHex(undefined), 0);
  assert.equal(parseHex("junk"), 0);
  assert.deepEqual(setBits(0x0000000a), [1, 3]);
  assert.deepEqual(setBits(0x80000000), [31]);
  assert.deepEqual(setBits(0), []);
});

const sample = (o: Partial<Parameters<typeof linkHealth>[0]> = {}) => ({
  frames: 0, rx_errors: 0, pd_watchdog_running: true, pd_watchdog_expiries: 0, esm: "OP", ...o,
});

test("link health from the slave's registers", () => {
  assert.deepEqual(linkHealth(sample({ frames: 1000 }), sample(), 1),
    { level: "ok", text: "process data cycling, 1000 frames/s" });
  assert.equal(linkHealth(sample({ rx_errors: 3 }), sample(), 1).level, "bad");
  assert.equal(linkHealth(sample({ pd_watchdog_expiries: 1 }), sample(), 1).level, "bad");
  assert.equal(linkHealth(sample({ pd_watchdog_running: false }), sample(), 1).level, "warn");
  assert.equal(linkHealth(sample({ esm: "PREOP" }), undefined, 0).level, "idle");
});
