// What both pages share: the token, the JSON API and the live stream.
const params = new URLSearchParams(location.search);
export const token = params.get('token') || '';

export function api(path, options = {}) {
  const headers = Object.assign({ 'X-Rise-Token': token }, options.headers || {});
  return fetch(path, Object.assign({}, options, { headers }));
}

export async function getJson(path) {
  const r = await api(path);
  if (!r.ok) throw new Error(path + ': HTTP ' + r.status);
  return r.json();
}

export function postJson(path, body, extra = {}) {
  return api(path, Object.assign({ method: 'POST', body: JSON.stringify(body),
                                   headers: { 'Content-Type': 'application/json' } }, extra));
}

// Server-Sent Events: calls onUpdate({channels, events, server_utime}) per push.
export function stream(onUpdate, onState) {
  const es = new EventSource('/api/stream?token=' + encodeURIComponent(token));
  es.onmessage = (e) => onUpdate(JSON.parse(e.data));
  es.onopen = () => onState && onState(true);
  es.onerror = () => onState && onState(false);
  return es;
}

export function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') e.className = v;
    else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c instanceof Node ? c : document.createTextNode(String(c)));
  return e;
}

export const ROBOT_COLOUR = 0xff5a00;  // the robot on the map and in the 3D view (the tests look for it)
