// The line (every slave, its state and link) and the Fusion.IO rack drawn as hardware: the
// control module with its Online LED, fan, temperature and one RIM port per RIM; each RIM with
// its RIM PORT and Power LEDs (guide §4.3), fans and slots; each slot with its card and
// channels. Values are updated in place from the stream.
import { h } from "./dom";
import { formatValue, linkHealth, LinkSample, parseHex } from "./format";
import { fusionOnlineLed, LedColor, rimLeds } from "./leds";
import { LiveFrame, LiveSlave, RackInfo, SlaveEntry } from "./types";

export type PickFn = (key: string, label: string) => void;
export type ActionFn = (path: string, body: unknown) => void;

function led(id: string, title: string): HTMLElement {
  return h("span", { class: "led off", id, title, "data-led": title }, "");
}
function setLed(id: string, color: LedColor): void {
  const el = document.getElementById(id);
  if (el) el.className = `led ${color}`;
}
function setText(id: string, text: string): void {
  const el = document.getElementById(id);
  if (el && el.textContent !== text) el.textContent = text;
}

export function channelKey(slave: number, module: number, dir: "in" | "out", ch: number): string {
  return `${slave}-${module}-${dir}-${ch}`;
}

export function renderLine(container: HTMLElement, slaves: SlaveEntry[]): void {
  const rows = [];
  for (const entry of slaves) {
    const s = entry.slave;
    rows.push(h("tr", { id: `line-${s}` },
      h("td", { id: `line-${s}-pos` }, String(s)),
      h("td", {}, entry.device ?? `Fusion.IO rack, ${entry.modules ?? 0} modules`),
      h("td", { id: `line-${s}-ident` }, ""),
      h("td", { id: `line-${s}-addr` }, ""),
      h("td", { id: `line-${s}-esm`, class: "esm" }, ""),
      h("td", { id: `line-${s}-al` }, ""),
      h("td", { id: `line-${s}-wkc` }, "")));
  }
  container.replaceChildren(h("table", { class: "grid" },
    h("thead", {}, h("tr", {}, ...["position", "device", "identity (vendor / product / revision)", "station",
      "ESM state", "AL status code", "working-counter health (slave's view)"].map((c) => h("th", {}, c)))),
    h("tbody", {}, ...rows)));
}

const previous = new Map<number, { sample: LinkSample; t: number }>();

export function updateLine(frame: LiveFrame): void {
  for (const s of frame.slaves) {
    setText(`line-${s.slave}-pos`, String(s.position));
    setText(`line-${s.slave}-ident`, `${s.vendor_id} / ${s.product_code} / ${s.revision}`);
    setText(`line-${s.slave}-addr`, s.station_address ? `0x${s.station_address.toString(16)}` : "-");
    setText(`line-${s.slave}-esm`, s.esm + ((s.al_status & 0x10) ? " (error)" : ""));
    setText(`line-${s.slave}-al`,
      `0x${s.al_status_code.toString(16).padStart(4, "0").toUpperCase()} ${s.al_status_text}`);
    const before = previous.get(s.slave);
    // Health over the last second or so (frames per second, new errors).
    if (!before || frame.t - before.t >= 1) {
      const health = linkHealth(s, before?.sample, before ? frame.t - before.t : 0);
      const cell = document.getElementById(`line-${s.slave}-wkc`);
      if (cell) {
        cell.textContent = health.text;
        cell.className = `health ${health.level}`;
      }
      previous.set(s.slave, { sample: { ...s }, t: frame.t });
    }
  }
}

export function renderRack(container: HTMLElement, slave: number, rack: RackInfo, pick: PickFn,
                           act: ActionFn): void {
  const cm = h("div", { class: "cm" },
    h("div", { class: "cm-title" }, `Control module (slave ${slave})`),
    h("div", { class: "leds" }, led(`s${slave}-online`, "Online"), h("span", {}, "Online")),
    h("div", {}, "CPU fan ", h("b", { id: `s${slave}-cpufan` }, "")),
    h("div", {}, "CPU temperature ", h("b", { id: `s${slave}-cputemp` }, "")),
    h("div", { class: "ports" }, ...rack.rims.map((r) =>
      h("div", { class: "port" }, led(`s${slave}-cmport-${r.rim}`, `RIM port ${r.rim}`), `RIM ${r.rim}`))));
  const rims = rack.rims.map((r) => {
    const mods = rack.modules.filter((m) => m.rim === r.rim).sort((a, b) => a.slot - b.slot);
    const slots = mods.map((m) => h("div", { class: "slot", "data-testid": `slot-${r.rim}-${m.slot}` },
      h("div", { class: "slot-head" }, h("b", {}, `slot ${m.slot}`), ` module ${m.module}`),
      h("div", { class: "card", title: m.description }, m.card),
      h("div", { class: "card-id" }, `${m.card_id} / ${m.module_ident}`),
      ...m.inputs.map((c) => {
        const key = channelKey(slave, m.module, "in", c.channel);
        return h("div", { class: "ch in", onclick: () => pick(key, `module ${m.module} ${m.card} input ${c.channel} (${c.unit})`) },
          h("span", {}, `in ${c.channel}`), h("span", { class: "val", id: `v-${key}`, "data-unit": c.unit }, formatValue(c.value, c.unit)));
      }),
      ...m.outputs.map((c) => {
        const key = channelKey(slave, m.module, "out", c.channel);
        return h("div", { class: "ch out", onclick: () => pick(key, `module ${m.module} ${m.card} output ${c.channel} (${c.unit})`) },
          h("span", {}, `out ${c.channel}`), h("span", { class: "val", id: `v-${key}`, "data-unit": c.unit }, formatValue(c.commanded, c.unit)));
      })));
    return h("div", { class: "rim", "data-testid": `rim-${r.rim}` },
      h("div", { class: "rim-head" },
        h("b", {}, `RIM ${r.rim}`),
        h("span", { class: "leds" }, led(`s${slave}-rimport-${r.rim}`, "RIM PORT"), "RIM PORT",
          led(`s${slave}-rimpower-${r.rim}`, "Power"), "Power"),
        h("span", { class: "rim-state", id: `s${slave}-rimstate-${r.rim}` }, r.state),
        h("span", { class: "fans", id: `s${slave}-rimfans-${r.rim}` }, ""),
        h("button", { onclick: () => act("/rim/unplug", { rim: r.rim }) }, `unplug RIM ${r.rim}`),
        h("button", { onclick: () => act("/rim/replug", { rim: r.rim }) }, `replug RIM ${r.rim}`)),
      h("div", { class: "slots" }, ...slots));
  });
  container.replaceChildren(h("div", { class: "rack" }, cm, ...rims));
}

export function updateRack(s: LiveSlave, units: Map<string, string>): void {
  const slave = s.slave;
  setLed(`s${slave}-online`, fusionOnlineLed(parseHex(s.F380), s.rims.map((r) => r.state)));
  setText(`s${slave}-cpufan`, `${s.cpu_fan_rpm.toFixed(0)} rpm`);
  setText(`s${slave}-cputemp`, `${s.cpu_temperature.toFixed(1)} °C`);
  for (const r of s.rims) {
    const leds = rimLeds(r.state);
    setLed(`s${slave}-cmport-${r.rim}`, leds.cmPort);
    setLed(`s${slave}-rimport-${r.rim}`, leds.rimPort);
    setLed(`s${slave}-rimpower-${r.rim}`, leds.rimPower);
    setText(`s${slave}-rimstate-${r.rim}`, r.state + (r.comm_error ? " (comm error)" : ""));
    setText(`s${slave}-rimfans-${r.rim}`,
      `fans: supply ${r.power_supply_rpm.toFixed(0)} rpm, slot ${r.slot_card_rpm.toFixed(0)} rpm`);
  }
  for (const m of s.modules) {
    m.in.forEach((v, c) => {
      const key = channelKey(slave, m.module, "in", c);
      setText(`v-${key}`, formatValue(v, units.get(key) ?? ""));
    });
    m.out.forEach((v, c) => {
      const key = channelKey(slave, m.module, "out", c);
      setText(`v-${key}`, formatValue(v[0], units.get(key) ?? ""));
    });
  }
}
