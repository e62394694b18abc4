// The LED table of guide §4.3, state by state.
import assert from "node:assert/strict";
import { test } from "node:test";
import { fusionOnlineLed, rimLeds } from "../src/leds";

test("online: RIM PORT, Power and the Fusion device's RIM port green", () => {
  assert.deepEqual(rimLeds("online"), { rimPort: "green", rimPower: "green", cmPort: "green" });
});

test("connected (and shut down for an error): RIM PORT amber, Power off, CM port amber", () => {
  assert.deepEqual(rimLeds("connected"), { rimPort: "amber", rimPower: "off", cmPort: "amber" });
  assert.deepEqual(rimLeds("error"), { rimPort: "amber", rimPower: "off", cmPort: "amber" });
});

test("offline (cable pulled, power removed): all off", () => {
  assert.deepEqual(rimLeds("offline"), { rimPort: "off", rimPower: "off", cmPort: "off" });
  assert.deepEqual(rimLeds("something else"), { rimPort: "off", rimPower: "off", cmPort: "off" });
});

test("Fusion Online LED green only without active exception and with every RIM online", () => {
  assert.equal(fusionOnlineLed(0, ["online", "online"]), "green");
  assert.equal(fusionOnlineLed(0x08, ["online", "online"]), "off");
  assert.equal(fusionOnlineLed(0, ["online", "connected"]), "off");
});
