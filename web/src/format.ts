// Numbers as the page shows them: engineering units, register values, link health.

// A value in its unit with a precision that suits it ("4.000 V", "12.35 mA", "21.4 °C").
export function formatValue(value: number | null, unit: string): string {
  if (value === null) return unit === "°C" || unit === "degC" ? "open" : "-";
  if (!Number.isFinite(value)) return "-";
  const u = unit === "degC" ? "°C" : unit;
  let text: string;
  if (u === "" || u === "counts" || u === "bool" || u === "bit") {
    text = Number.isInteger(value) ? value.toFixed(0) : value.toFixed(3);
  } else if (u === "°C") {
    text = value.toFixed(1);
  } else if (Math.abs(value) >= 100) {
    text = value.toFixed(1);
  } else {
    text = value.toFixed(3);
  }
  return u ? `${text} ${u}` : text;
}

export function hex(value: number, digits: number): string {
  return "0x" + (value >>> 0).toString(16).toUpperCase().padStart(digits, "0");
}

// "0x00000C04" -> 3076; anything else -> 0.
export function parseHex(text: string | undefined): number {
  if (!text) return 0;
  const v = Number.parseInt(text, 16);
  return Number.isFinite(v) ? v >>> 0 : 0;
}

// The numbers of the bits set in a 32-bit word, lowest first.
export function setBits(word: number): number[] {
  const bits: number[] = [];
  for (let b = 0; b < 32; b++) if ((word >>> b) & 1) bits.push(b);
  return bits;
}

export interface LinkSample {
  frames: number;
  rx_errors: number;
  pd_watchdog_running: boolean;
  pd_watchdog_expiries: number;
  esm: string;
}

export interface LinkHealth {
  level: "ok" | "warn" | "bad" | "idle";
  text: string;
}

// Working-counter health as the slave sees it: in SAFEOP/OP the master's process data keep
// the process-data watchdog (ETG.1000.4 §6.7.2, 0x0440 bit 0) running; an expiry (0x0442
// counts them) or new RX errors (0x0300..) mean frames went missing or arrived damaged, which
// the master sees as a wrong working counter.
export function linkHealth(now: LinkSample, before: LinkSample | undefined, seconds: number): LinkHealth {
  const rate = before && seconds > 0 ? Math.max(0, (now.frames - before.frames) / seconds) : 0;
  const rateText = `${rate.toFixed(0)} frames/s`;
  if (before && now.rx_errors > before.rx_errors) {
    return { level: "bad", text: `RX errors +${now.rx_errors - before.rx_errors}, ${rateText}` };
  }
  if (before && now.pd_watchdog_expiries !== before.pd_watchdog_expiries) {
    return { level: "bad", text: `process data watchdog expired, ${rateText}` };
  }
  if (now.esm === "SAFEOP" || now.esm === "OP") {
    return now.pd_watchdog_running
      ? { level: "ok", text: `process data cycling, ${rateText}` }
      : { level: "warn", text: `no process data, ${rateText}` };
  }
  return { level: "idle", text: `no process data in ${now.esm}, ${rateText}` };
}
