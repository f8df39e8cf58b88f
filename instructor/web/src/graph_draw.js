// The training graph drawn in SVG: START, the tasks and END as boxes in
// columns by their distance from START (breadth first), transitions as
// arrows with their order number and condition, a repeat (a task to itself)
// as a loop over its box. No library: the graph is small.
const NS = 'http://www.w3.org/2000/svg';
const BOX_W = 150, BOX_H = 54, COL_W = 300, ROW_H = 150, MARGIN = 60;

function svg(tag, attrs = {}, text) {
  const e = document.createElementNS(NS, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

// Column of every vertex: START 0, a task its BFS depth, END after the last.
export function layout(graph) {
  const names = graph.nodes.map((n) => n.name);
  const depth = new Map([['START', 0]]);
  const queue = ['START'];
  while (queue.length) {
    const v = queue.shift();
    for (const t of graph.transitions) {
      if (t.from !== v || t.to === 'END' || !names.includes(t.to) || depth.has(t.to)) continue;
      depth.set(t.to, depth.get(v) + 1);
      queue.push(t.to);
    }
  }
  for (const n of names) if (!depth.has(n)) depth.set(n, 1);  // unreachable: the validator says so
  const last = Math.max(1, ...names.map((n) => depth.get(n))) + 1;
  depth.set('END', names.length ? last : 1);
  const rows = new Map();
  const pos = new Map();
  for (const v of ['START', ...names, 'END']) {
    const col = depth.get(v);
    const row = rows.get(col) || 0;
    rows.set(col, row + 1);
    pos.set(v, { x: MARGIN + col * COL_W, y: MARGIN + 30 + row * ROW_H, col, row });
  }
  const height = MARGIN * 2 + 30 + Math.max(...rows.values()) * ROW_H;
  return { pos, width: MARGIN * 2 + (depth.get('END') + 1) * COL_W - (COL_W - BOX_W), height };
}

function edgePath(a, b, bend) {
  // Forward: right side to left side; in one column: down (or up) the left
  // side, clear of the repeat loops on top and of the edges coming in from
  // the left; backward: under the boxes.
  if (b.x === a.x) {
    const down = b.y > a.y;
    const p0 = { x: a.x + BOX_W * 0.85, y: down ? a.y + BOX_H : a.y };
    const p2 = { x: b.x + BOX_W * 0.85, y: down ? b.y : b.y + BOX_H };
    const c = { x: p0.x + 40 + bend, y: (p0.y + p2.y) / 2 };
    return { d: `M${p0.x},${p0.y} Q${c.x},${c.y} ${p2.x},${p2.y}`, mid: mid(p0, c, p2) };
  }
  if (b.x > a.x) {
    const p0 = { x: a.x + BOX_W, y: a.y + BOX_H / 2 }, p2 = { x: b.x, y: b.y + BOX_H / 2 };
    const c = { x: (p0.x + p2.x) / 2, y: (p0.y + p2.y) / 2 + bend };
    return { d: `M${p0.x},${p0.y} Q${c.x},${c.y} ${p2.x},${p2.y}`, mid: mid(p0, c, p2) };
  }
  const p0 = { x: a.x + BOX_W * 0.35, y: a.y + BOX_H }, p2 = { x: b.x + BOX_W * 0.65, y: b.y + BOX_H };
  const c = { x: (p0.x + p2.x) / 2, y: Math.max(p0.y, p2.y) + 50 + Math.abs(bend) };
  return { d: `M${p0.x},${p0.y} Q${c.x},${c.y} ${p2.x},${p2.y}`, mid: mid(p0, c, p2) };
}

function loopPath(a, k) {
  const h = 34 + k * 22;
  const p0 = { x: a.x + BOX_W * 0.3, y: a.y }, p2 = { x: a.x + BOX_W * 0.7, y: a.y };
  return { d: `M${p0.x},${p0.y} C${p0.x - 20},${a.y - h} ${p2.x + 20},${a.y - h} ${p2.x},${p2.y}`,
           mid: { x: a.x + BOX_W / 2, y: a.y - h * 0.75 - 3 } };
}

const mid = (p0, c, p2) => ({ x: 0.25 * p0.x + 0.5 * c.x + 0.25 * p2.x, y: 0.25 * p0.y + 0.5 * c.y + 0.25 * p2.y });

// The label of transition i: its number among those leaving its node, the condition.
export function edgeLabel(graph, i) {
  const t = graph.transitions[i];
  const order = graph.transitions.slice(0, i + 1).filter((x) => x.from === t.from).length;
  return `${order}: ${t.if ? t.if : 'always'}`;
}

// Draws `graph` into the <svg>; `bad` holds "nodes[i]" / "transitions[j]" with errors,
// `picked` the box clicked, `fresh` the index of the transition just added.
export function draw(el, graph, { bad = new Set(), picked = '', fresh = -1, onPick = () => {} } = {}) {
  const { pos, width, height } = layout(graph);
  el.replaceChildren();
  el.style.maxWidth = width + 'px';  // scaled down to the page's width, never up
  el.setAttribute('viewBox', `0 0 ${width} ${height}`);
  const defs = svg('defs');
  for (const [id, colour] of [['arrow', '#8b949e'], ['arrow-new', '#7ee787'], ['arrow-bad', '#ff7b72']]) {
    const m = svg('marker', { id, viewBox: '0 0 10 10', refX: 9, refY: 5, markerWidth: 7, markerHeight: 7, orient: 'auto-start-reverse' });
    m.append(svg('path', { d: 'M0,0 L10,5 L0,10 z', fill: colour }));
    defs.append(m);
  }
  el.append(defs);
  const pairs = new Map(), loops = new Map();
  graph.transitions.forEach((t, i) => {
    const a = pos.get(t.from), b = pos.get(t.to);
    if (!a || !b) return;  // an unknown end: the validator names it
    let p;
    if (t.from === t.to) {
      const k = loops.get(t.from) || 0;
      loops.set(t.from, k + 1);
      p = loopPath(a, k);
    } else {
      const key = [t.from, t.to].sort().join('\u0000');
      const k = pairs.get(key) || 0;
      pairs.set(key, k + 1);
      p = edgePath(a, b, (k % 2 ? 1 : -1) * Math.ceil(k / 2) * 34);
    }
    const isBad = bad.has(`transitions[${i}]`), isNew = i === fresh;
    const g = svg('g', { class: 'edge' + (isBad ? ' bad' : '') + (isNew ? ' new' : ''), 'data-index': i,
                         'data-from': t.from, 'data-to': t.to });
    g.append(svg('path', { d: p.d, 'marker-end': `url(#${isBad ? 'arrow-bad' : isNew ? 'arrow-new' : 'arrow'})` }));
    const label = edgeLabel(graph, i) + (t.from === t.to ? ' ↻' : '');
    g.append(svg('text', { x: p.mid.x, y: p.mid.y, 'text-anchor': 'middle' }, label));
    el.append(g);
  });
  const boxes = [['START', null], ...graph.nodes.map((n, i) => [n.name, n, i]), ['END', null]];
  for (const [name, node, i] of boxes) {
    const p = pos.get(name);
    const g = svg('g', { class: 'node', 'data-name': name });
    const cls = 'box' + (node ? '' : ' terminal') + (bad.has(`nodes[${i}]`) ? ' bad' : '') + (picked === name ? ' picked' : '');
    const rect = svg('rect', { class: cls, x: p.x, y: p.y, width: BOX_W, height: BOX_H, rx: node ? 6 : 27 });
    rect.addEventListener('click', () => onPick(name));
    g.append(rect);
    g.append(svg('text', { x: p.x + BOX_W / 2, y: p.y + (node ? 19 : 32), 'text-anchor': 'middle', 'font-weight': 'bold' }, name));
    if (node) {
      g.append(svg('text', { x: p.x + BOX_W / 2, y: p.y + 34, 'text-anchor': 'middle', class: 'small' }, node.task));
      g.append(svg('text', { x: p.x + BOX_W / 2, y: p.y + 48, 'text-anchor': 'middle', class: 'small' },
                   `at most ${node.max_attempts} attempt${node.max_attempts === 1 ? '' : 's'}`));
    }
    el.append(g);
  }
}
