// Fetching a file for a viewer: its bytes and name, with its progress as the bytes arrive. The
// Viewer's load() and the <raypipe-viewer> element's src both take files so.

/// The file at `source` (a URL, relative to the document): `{ bytes, name }`, the name the last
/// segment of the URL it came from. `progress(loaded, total)` hears each chunk (`total` 0 where
/// the server sends no length). Rejects with `SOURCE: cannot fetch: why`.
export async function fetchFile(source, progress = () => {}) {
  const url = new URL(source, document.baseURI);
  let response;
  try {
    response = await fetch(url);
    if (!response.ok) throw new Error(`HTTP ${response.status} ${response.statusText}`.trimEnd());
  } catch (error) {
    throw new Error(`${source}: cannot fetch: ${error.message}`);
  }
  const name = decodeURIComponent(new URL(response.url || url).pathname.split("/").pop() || String(source));
  const total = Number(response.headers.get("content-length")) || 0;
  const reader = response.body.getReader();
  const chunks = [];
  let loaded = 0;
  for (;;) {
    const { done, value } = await reader.read();
    if (done) break;
    chunks.push(value);
    loaded += value.length;
    progress(loaded, total);
  }
  const bytes = new Uint8Array(loaded);
  let at = 0;
  for (const chunk of chunks) {
    bytes.set(chunk, at);
    at += chunk.length;
  }
  return { bytes, name };
}
