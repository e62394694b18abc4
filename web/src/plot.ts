// The plot of one channel over the last seconds: own canvas code (a line, its range, a time
// axis), redrawn on every snapshot.
import { Series, valueRange } from "./history";

export function drawPlot(canvas: HTMLCanvasElement, series: Series | undefined, now: number,
                         seconds: number, label: string): void {
  const ctx = canvas.getContext("2d");
  if (!ctx) return;
  const w = canvas.width;
  const hgt = canvas.height;
  ctx.clearRect(0, 0, w, hgt);
  ctx.fillStyle = "#10151c";
  ctx.fillRect(0, 0, w, hgt);
  ctx.fillStyle = "#9fb3c8";
  ctx.font = "12px sans-serif";
  ctx.fillText(label, 8, 14);
  if (!series) return;
  const { t, v } = series.since(now - seconds);
  if (t.length < 2) return;
  const [lo, hi] = valueRange(v);
  const left = 56;
  const top = 20;
  const pw = w - left - 8;
  const ph = hgt - top - 20;
  const x = (time: number) => left + ((time - (now - seconds)) / seconds) * pw;
  const y = (val: number) => top + (1 - (val - lo) / (hi - lo)) * ph;
  ctx.strokeStyle = "#2a3644";
  ctx.beginPath();
  for (let i = 0; i <= 4; i++) {
    const gy = top + (ph * i) / 4;
    ctx.moveTo(left, gy);
    ctx.lineTo(left + pw, gy);
  }
  ctx.stroke();
  ctx.fillStyle = "#9fb3c8";
  for (let i = 0; i <= 4; i++) {
    const val = hi - ((hi - lo) * i) / 4;
    ctx.fillText(val.toPrecision(4), 4, top + (ph * i) / 4 + 4);
  }
  ctx.fillText(`-${seconds} s`, left, hgt - 4);
  ctx.fillText("now", left + pw - 24, hgt - 4);
  ctx.strokeStyle = "#4fc3f7";
  ctx.lineWidth = 1.5;
  ctx.beginPath();
  ctx.moveTo(x(t[0]), y(v[0]));
  for (let i = 1; i < t.length; i++) ctx.lineTo(x(t[i]), y(v[i]));
  ctx.stroke();
}
