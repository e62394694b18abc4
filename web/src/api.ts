// The control API as the page calls it: the session cookie goes along by itself (same origin);
// bodies are JSON (the API refuses anything else).
export interface ApiResult {
  status: number;
  body: unknown;
}

export async function callApi(method: "GET" | "POST", path: string, body?: unknown): Promise<ApiResult> {
  const init: RequestInit = { method, credentials: "same-origin", headers: {} };
  if (method === "POST") {
    init.headers = { "Content-Type": "application/json" };
    init.body = JSON.stringify(body ?? {});
  }
  const r = await fetch(path, init);
  let parsed: unknown = null;
  const text = await r.text();
  try {
    parsed = text ? JSON.parse(text) : null;
  } catch {
    parsed = text;
  }
  return { status: r.status, body: parsed };
}

// /api/... of slave 0 is also /api/slaves/0/...; the page always names the slave.
export function slavePath(slave: number, rest: string): string {
  return `/api/slaves/${slave}${rest}`;
}
