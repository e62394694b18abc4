// The exception tree (0xF380..0xF398, 0x2rr1:08; guide §3) and the 0x10F3 diagnosis history
// (ETG.1020 ch. 13) as tables: each word with the numbers of its set bits.
import { h } from "./dom";
import { parseHex, setBits } from "./format";

interface Exceptions {
  F380: string; F390: string; F386: string; F388: string; F396: string; F398: string;
  device_event_status: string;
  rims: { rim: number; state: string; event_status: string }[];
  modules: { module: number; F382: string; F384: string; F392: string; F394: string }[];
}
interface Diagnosis {
  maximum_messages: number; newest_message: number; flags: string; mode: string;
  messages: { subindex: number; diag_code: string; type: string; text_id: string; time_ns: number;
    rim: number; module: number; channel: number | null; text: string; acknowledged: boolean }[];
}

function word(text: string): HTMLElement {
  const bits = setBits(parseHex(text));
  return h("td", { class: bits.length ? "set" : "" }, text, bits.length ? `  bits ${bits.join(", ")}` : "");
}

export function renderExceptions(container: HTMLElement, body: unknown): void {
  const e = body as Exceptions;
  if (!e || typeof e.F380 !== "string") {
    container.replaceChildren(h("pre", {}, JSON.stringify(body, null, 2)));
    return;
  }
  const rows: [string, string, string][] = [
    ["0xF380 / 0xF390", "summary (active / latched)", ""],
    ["0xF386 / 0xF396", "global warnings (active / latched)", ""],
    ["0xF388 / 0xF398", "global errors (active / latched)", ""],
  ];
  const words: [string, string][] = [[e.F380, e.F390], [e.F386, e.F396], [e.F388, e.F398]];
  const body1 = rows.map((r, i) => h("tr", {}, h("td", {}, r[0]), h("td", {}, r[1]), word(words[i][0]), word(words[i][1])));
  body1.push(h("tr", {}, h("td", {}, "0x2000:0A"), h("td", {}, "device event status"), word(e.device_event_status), h("td", {}, "")));
  for (const r of e.rims) {
    body1.push(h("tr", { "data-testid": `exc-rim-${r.rim}` }, h("td", {}, `0x2${r.rim}01:08`),
      h("td", {}, `RIM ${r.rim} event status (${r.state})`), word(r.event_status), h("td", {}, "")));
  }
  for (const m of e.modules) {
    body1.push(h("tr", {}, h("td", {}, `0xF382/4 ... module ${m.module}`), h("td", {}, "module warnings / errors (active)"), word(m.F382), word(m.F384)));
    body1.push(h("tr", {}, h("td", {}, `0xF392/4 ... module ${m.module}`), h("td", {}, "module warnings / errors (latched)"), word(m.F392), word(m.F394)));
  }
  container.replaceChildren(h("table", { class: "grid", id: "exceptions-table" },
    h("thead", {}, h("tr", {}, ...["object", "meaning", "active", "latched"].map((c) => h("th", {}, c)))),
    h("tbody", {}, ...body1)));
}

export function renderDiagnosis(container: HTMLElement, body: unknown): void {
  const d = body as Diagnosis;
  if (!d || !Array.isArray(d.messages)) {
    container.replaceChildren(h("pre", {}, JSON.stringify(body, null, 2)));
    return;
  }
  const rows = d.messages.slice().reverse().map((m) => h("tr", { class: m.type },
    h("td", {}, String(m.subindex)), h("td", {}, m.type), h("td", {}, m.diag_code), h("td", {}, m.text_id),
    h("td", {}, (m.time_ns / 1e9).toFixed(3)), h("td", {}, String(m.rim)), h("td", {}, String(m.module)),
    h("td", {}, m.channel === null ? "-" : String(m.channel)), h("td", {}, m.acknowledged ? "yes" : ""),
    h("td", {}, m.text)));
  container.replaceChildren(
    h("div", {}, `0x10F3: ${d.messages.length} of ${d.maximum_messages} messages, mode ${d.mode}, flags ${d.flags}, newest subindex ${d.newest_message}`),
    h("table", { class: "grid", id: "diagnosis-table" },
      h("thead", {}, h("tr", {}, ...["sub", "type", "diag code", "text ID", "time s", "RIM", "module", "channel", "ack", "text"].map((c) => h("th", {}, c)))),
      h("tbody", {}, ...rows)));
}
