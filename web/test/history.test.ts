import assert from "node:assert/strict";
import { test } from "node:test";
import { History, Series, valueRange } from "../src/history";

test("a series keeps the newest points, oldest first", () => {
  const s = new Series(3);
  for (let i = 0; i < 5; i++) s.push(i, i * 10);
  assert.equal(s.length, 3);
  assert.deepEqual(s.since(0), { t: [2, 3, 4], v: [20, 30, 40] });
  assert.deepEqual(s.since(3.5), { t: [4], v: [40] });
});

test("history per channel key", () => {
  const h = new History(10);
  h.push("0-2-in-0", 1, 0);
  h.push("0-2-in-0", 2, 1);
  assert.deepEqual(h.get("0-2-in-0")?.since(0), { t: [1, 2], v: [0, 1] });
  assert.equal(h.get("0-1-out-0"), undefined);
});

test("value range never collapses", () => {
  assert.deepEqual(valueRange([]), [0, 1]);
  const [lo, hi] = valueRange([2, 2]);
  assert.ok(lo < 2 && hi > 2);
  const [a, b] = valueRange([0, 10]);
  assert.ok(Math.abs(a + 0.5) < 1e-9 && Math.abs(b - 10.5) < 1e-9);
});
