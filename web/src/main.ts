// The live page: line view, rack, channels with a plot, fault forms, exception tree and
// diagnosis history. Data: GET /api/slaves and /api/slaves/N/rack once, then the snapshot
// stream GET /api/stream (server-sent events, ~20 per second); tables are fetched again when
// the stream shows their summary changed.
import { callApi, slavePath } from "./api";
import { renderControls } from "./controls";
import { byId } from "./dom";
import { History } from "./history";
import { drawPlot } from "./plot";
import { channelKey, renderLine, renderRack, updateLine, updateRack } from "./rack_view";
import { renderDiagnosis, renderExceptions } from "./tables";
import { LiveFrame, LiveSlave, RackInfo, SlaveEntry } from "./types";

const history = new History(60 * 25);
const units = new Map<string, string>();
let slave = 0;
let picked = "";
let pickedLabel = "";
let lastFrame: LiveFrame | null = null;
let tableKey = "";
const arrivals: number[] = [];

function showResult(text: string): void {
  byId("result").textContent = text;
}

async function send(method: "GET" | "POST", rest: string, body?: unknown): Promise<void> {
  const r = await callApi(method, slavePath(slave, rest), body);
  showResult(`${method} ${slavePath(slave, rest)} -> ${r.status}\n${JSON.stringify(r.body, null, 2)}`);
  await refreshTables();
}

async function refreshTables(): Promise<void> {
  const [e, d] = await Promise.all([
    callApi("GET", slavePath(slave, "/exceptions")),
    callApi("GET", slavePath(slave, "/diagnosis")),
  ]);
  renderExceptions(byId("exceptions"), e.body);
  renderDiagnosis(byId("diagnosis"), d.body);
}

async function loadSlave(n: number): Promise<void> {
  slave = n;
  const r = await callApi("GET", slavePath(n, "/rack"));
  if (r.status !== 200) {
    showResult(`GET rack -> ${r.status}\n${JSON.stringify(r.body)}`);
    return;
  }
  const rack = r.body as RackInfo;
  units.clear();
  for (const m of rack.modules) {
    for (const c of m.inputs) units.set(channelKey(n, m.module, "in", c.channel), c.unit);
    for (const c of m.outputs) units.set(channelKey(n, m.module, "out", c.channel), c.unit);
  }
  const types = Array.from(new Set(rack.modules.map((m) => m.card))).sort();
  byId("card-types").textContent = `card types in this rack: ${types.join(", ")}`;
  byId("rack-esm").textContent = `ESM ${rack.esm}, outputs ${rack.outputs_valid ? "valid" : "not valid"}, ` +
    `Detect Modules Override ${rack.detect_modules_override ? 1 : 0}`;
  renderRack(byId("rack"), n, rack, (key, label) => {
    picked = key;
    pickedLabel = label;
    byId("plot-label").textContent = label;
  }, (path, body) => void send("POST", path, body));
  renderControls(byId("controls"), rack, (m, p, b) => void send(m, p, b), showResult);
  tableKey = "";
  await refreshTables();
}

function onFrame(frame: LiveFrame): void {
  lastFrame = frame;
  const now = performance.now();
  arrivals.push(now);
  while (arrivals.length && arrivals[0] < now - 1000) arrivals.shift();
  byId("rate").textContent = `${arrivals.length} updates/s`;
  updateLine(frame);
  const s: LiveSlave | undefined = frame.slaves[slave];
  if (!s || !s.rack) return;
  byId("rack-esm").textContent = `ESM ${s.esm}, outputs ${s.outputs_valid ? "valid" : "not valid"}`;
  updateRack(s, units);
  for (const m of s.modules) {
    m.in.forEach((v, c) => { if (v !== null) history.push(channelKey(slave, m.module, "in", c), frame.t, v); });
    m.out.forEach((v, c) => history.push(channelKey(slave, m.module, "out", c), frame.t, v[0]));
  }
  const seconds = Number((byId("plot-window") as HTMLSelectElement).value);
  if (picked) drawPlot(byId("plot") as HTMLCanvasElement, history.get(picked), frame.t, seconds, pickedLabel);
  const key = [s.F380, s.F390, s.device_event_status, s.diagnosis_newest, s.diagnosis_messages,
    ...s.rims.map((r) => r.event_status + r.state)].join();
  if (key !== tableKey) {
    tableKey = key;
    void refreshTables();
  }
}

function openStream(): void {
  const es = new EventSource("/api/stream");
  es.onmessage = (ev) => onFrame(JSON.parse(ev.data) as LiveFrame);
  es.onerror = () => { byId("rate").textContent = "stream interrupted, reconnecting"; };
}

async function start(): Promise<void> {
  const r = await callApi("GET", "/api/slaves");
  if (r.status !== 200) {
    showResult(`GET /api/slaves -> ${r.status}\n${JSON.stringify(r.body)}`);
    return;
  }
  const list = (r.body as { slaves: SlaveEntry[] }).slaves;
  renderLine(byId("line"), list);
  const racks = list.filter((s) => s.device === undefined);
  const pickSlave = byId("slave") as HTMLSelectElement;
  pickSlave.replaceChildren(...racks.map((s) => new Option(`slave ${s.slave}`, String(s.slave))));
  pickSlave.onchange = () => void loadSlave(Number(pickSlave.value));
  byId("clear").onclick = () => void send("POST", "/exceptions/clear", {});
  if (racks.length > 0) await loadSlave(racks[0].slave);
  else showResult("no Fusion.IO rack in this line: the line view above shows every device");
  openStream();
  void lastFrame;
}

void start();
