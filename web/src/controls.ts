// A form for every command `rackcat ctl` has (docs/MODULES.md "Control API"), each sending
// one request and showing the API's answer, and a free request form for any other endpoint.
import { h } from "./dom";
import { RackInfo } from "./types";

export type SendFn = (method: "GET" | "POST", rest: string, body?: unknown) => void;
export type ReportFn = (text: string) => void;

function field(name: string, attrs: Record<string, string> = {}): HTMLElement {
  return h("label", {}, name, " ", h("input", { name, ...attrs }));
}
function select(name: string, options: (string | number)[]): HTMLElement {
  return h("label", {}, name, " ", h("select", { name }, ...options.map((o) => h("option", { value: String(o) }, String(o)))));
}
function check(name: string): HTMLElement {
  return h("label", {}, h("input", { name, type: "checkbox" }), " ", name);
}

function values(form: HTMLFormElement): Record<string, string | boolean> {
  const out: Record<string, string | boolean> = {};
  for (const el of Array.from(form.elements) as HTMLInputElement[]) {
    if (!el.name) continue;
    out[el.name] = el.type === "checkbox" ? el.checked : el.value;
  }
  return out;
}
const num = (s: string | boolean) => Number(s);

interface Command { title: string; fields: HTMLElement[]; build: (v: Record<string, string | boolean>) => [string, unknown] }

export function renderControls(container: HTMLElement, rack: RackInfo, send: SendFn, report: ReportFn): void {
  const rims = rack.rims.map((r) => r.rim);
  const modules = rack.modules.map((m) => m.module);
  const cmds: Command[] = [
    { title: "Unplug RIM", fields: [select("rim", rims), check("comm_error")], build: (v) => ["/rim/unplug", { rim: num(v.rim), comm_error: v.comm_error }] },
    { title: "Replug RIM", fields: [select("rim", rims)], build: (v) => ["/rim/replug", { rim: num(v.rim) }] },
    { title: "RIM state", fields: [select("rim", rims), select("state", ["online", "connected", "offline", "error"]), check("comm_error")],
      build: (v) => ["/rim/state", { rim: num(v.rim), state: v.state, comm_error: v.comm_error }] },
    { title: "RIM safety-controller errors", fields: [select("rim", rims), check("slot_machine_mcm0"), check("sout_compare_mcm0"), check("slot_machine_mcm1"), check("sout_compare_mcm1")],
      build: (v) => ["/rim/mcm", { rim: num(v.rim), errors: ["slot_machine_mcm0", "sout_compare_mcm0", "slot_machine_mcm1", "sout_compare_mcm1"].filter((k) => v[k]) }] },
    { title: "Fan RPM", fields: [select("rim", [0, ...rims]), select("zone", ["", "cpu", "power_supply", "slot_card"]), field("rpm", { value: "3000", type: "number" })],
      build: (v) => ["/fan", v.zone ? { rim: num(v.rim), zone: v.zone, rpm: num(v.rpm) } : { rim: num(v.rim), rpm: num(v.rpm) }] },
    { title: "CPU temperature", fields: [field("celsius", { value: "45", type: "number", step: "any" }), check("immediate")],
      build: (v) => ["/cpu_temperature", { celsius: num(v.celsius), immediate: v.immediate }] },
    { title: "Channel value / source", fields: [select("module", modules), field("channel", { value: "0", type: "number" }), field("value", { placeholder: "constant value" }),
      field("source", { placeholder: "or source kind (sine, ramp, replay...)" }), field("params", { placeholder: '{"amplitude": 2}' })],
      build: (v) => ["/channel", v.value !== "" ? { module: num(v.module), channel: num(v.channel), value: num(v.value) }
        : { module: num(v.module), channel: num(v.channel), source: v.source, params: v.params ? JSON.parse(String(v.params)) : {} }] },
    { title: "Wiring fault", fields: [select("module", modules), field("channel", { value: "0", type: "number" }), select("fault", ["none", "safe", "unsafe"])],
      build: (v) => ["/wiring_fault", { module: num(v.module), channel: num(v.channel), fault: v.fault }] },
    { title: "Output fault", fields: [select("module", modules), field("channel", { value: "0", type: "number" }), check("overload"), check("overtemperature")],
      build: (v) => ["/output_fault", { module: num(v.module), channel: num(v.channel), overload: v.overload, overtemperature: v.overtemperature }] },
    { title: "Sensor", fields: [select("module", modules), field("channel", { value: "0", type: "number" }), check("open"), field("loop_ohms", { placeholder: "ohms (optional)" })],
      build: (v) => ["/sensor", v.loop_ohms !== "" ? { module: num(v.module), channel: num(v.channel), open: v.open, loop_ohms: num(v.loop_ohms) }
        : { module: num(v.module), channel: num(v.channel), open: v.open }] },
    { title: "UART inject", fields: [select("module", modules), field("channel", { value: "0", type: "number" }), field("text"), select("error", ["", "overflow", "framing", "parity", "tx_overflow"])],
      build: (v) => ["/uart/inject", { module: num(v.module), channel: num(v.channel), ...(v.text ? { text: v.text } : {}), ...(v.error ? { error: v.error } : {}) }] },
  ];
  const forms = cmds.map((c) => {
    const form = h("form", { class: "cmd" }, h("b", {}, c.title), ...c.fields, h("button", { type: "submit" }, "send")) as HTMLFormElement;
    form.addEventListener("submit", (ev) => {
      ev.preventDefault();
      try {
        const [path, body] = c.build(values(form));
        send("POST", path, body);
      } catch (err) {
        report(`not sent: ${String(err)}`);
      }
    });
    return form;
  });
  // Anything else the API offers (new endpoints included): method, path, JSON body.
  const raw = h("form", { class: "cmd" }, h("b", {}, "Any request"), select("method", ["GET", "POST"]),
    field("path", { value: "/esm", size: "24" }), field("body", { value: "{}", size: "30" }),
    h("button", { type: "submit" }, "send")) as HTMLFormElement;
  raw.addEventListener("submit", (ev) => {
    ev.preventDefault();
    const v = values(raw);
    let body: unknown = undefined;
    try {
      body = v.method === "POST" ? JSON.parse(String(v.body || "{}")) : undefined;
    } catch (err) {
      report(`not sent: the body is not JSON: ${String(err)}`);
      return;
    }
    send(v.method === "POST" ? "POST" : "GET", String(v.path), body);
  });
  container.replaceChildren(...forms, raw);
}
