// The last minute of every channel, for the plot: a fixed ring of (time, value) per channel.
export class Series {
  private readonly t: Float64Array;
  private readonly v: Float64Array;
  private start = 0;
  private count = 0;

  constructor(readonly capacity: number) {
    this.t = new Float64Array(capacity);
    this.v = new Float64Array(capacity);
  }

  push(time: number, value: number): void {
    const at = (this.start + this.count) % this.capacity;
    this.t[at] = time;
    this.v[at] = value;
    if (this.count < this.capacity) this.count++;
    else this.start = (this.start + 1) % this.capacity;
  }

  get length(): number {
    return this.count;
  }

  // The points with time >= since, oldest first.
  since(since: number): { t: number[]; v: number[] } {
    const t: number[] = [];
    const v: number[] = [];
    for (let i = 0; i < this.count; i++) {
      const k = (this.start + i) % this.capacity;
      if (this.t[k] >= since) {
        t.push(this.t[k]);
        v.push(this.v[k]);
      }
    }
    return { t, v };
  }
}

export class History {
  private readonly series = new Map<string, Series>();
  constructor(private readonly capacity: number) {}

  push(key: string, time: number, value: number): void {
    let s = this.series.get(key);
    if (!s) {
      s = new Series(this.capacity);
      this.series.set(key, s);
    }
    s.push(time, value);
  }

  get(key: string): Series | undefined {
    return this.series.get(key);
  }
}

// Axis limits with a little room, never a zero-height range.
export function valueRange(values: number[]): [number, number] {
  if (values.length === 0) return [0, 1];
  let lo = Math.min(...values);
  let hi = Math.max(...values);
  if (hi - lo < 1e-9) {
    lo -= 0.5;
    hi += 0.5;
  }
  const pad = (hi - lo) * 0.05;
  return [lo - pad, hi + pad];
}
