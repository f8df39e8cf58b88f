// The top-down map of a world (/api/world's boxes and regions), x to the
// right and y up, shared by the instructor console (console.js: robots and
// trails over it) and the Environment Builder (world_builder.js: the
// selection and its handles over it).

export const MAP_FILLS = { wall: '#8b949e', door: '#a0522d', stairs: '#4c6ef5', box: '#6e7681', prop: '#6e5494' };

// The xy extent of the world's boxes and regions, of `points` and of 3 m
// around the robot's start.
export function worldBounds(world, points = []) {
  let min = [Infinity, Infinity], max = [-Infinity, -Infinity];
  const grow = (x, y) => { min = [Math.min(min[0], x), Math.min(min[1], y)]; max = [Math.max(max[0], x), Math.max(max[1], y)]; };
  for (const b of world.boxes) {
    // The footprint's corners (a long wall's circle would take the map's room).
    const c = Math.cos(b.yaw), s = Math.sin(b.yaw), hx = b.size[0] / 2, hy = b.size[1] / 2;
    for (const [x, y] of [[hx, hy], [hx, -hy], [-hx, hy], [-hx, -hy]]) grow(b.center[0] + c * x - s * y, b.center[1] + s * x + c * y);
  }
  for (const r of world.regions) { grow(r.min[0], r.min[1]); grow(r.max[0], r.max[1]); }
  for (const p of points) grow(p[0], p[1]);
  grow(world.robot_start[0] - 3, world.robot_start[1] - 3);
  grow(world.robot_start[0] + 3, world.robot_start[1] + 3);
  return { min, max };
}

// The scale and the mappings between world metres and canvas pixels for
// `bounds` fitted into `canvas` with `margin` metres around.
export function mapFrame(canvas, bounds, margin = 0.5) {
  const { min, max } = bounds;
  const s = Math.min(canvas.width / (max[0] - min[0] + 2 * margin), canvas.height / (max[1] - min[1] + 2 * margin));
  const px = (x, y) => [(x - min[0] + margin) * s, canvas.height - (y - min[1] + margin) * s];
  const world = (u, v) => [u / s + min[0] - margin, (canvas.height - v) / s + min[1] - margin];
  return { s, px, world, min, max, canvas };
}

// A box `size` (along yaw, across) centred at `center`, turned by `yaw`.
export function drawBox(g, frame, center, size, yaw, fill) {
  const { s, px } = frame;
  g.save();
  const [cx, cy] = px(center[0], center[1]);
  g.translate(cx, cy); g.rotate(-yaw);
  g.fillStyle = fill; g.fillRect(-size[0] * s / 2, -size[1] * s / 2, size[0] * s, size[1] * s);
  g.restore();
}

// Background, 1 m grid, regions (named) and the static boxes by kind, over
// `bounds` (default: the world's and `points`' extent); returns the frame.
export function drawWorldMap(canvas, world, { points = [], bounds = null } = {}) {
  const g = canvas.getContext('2d');
  g.fillStyle = '#101215'; g.fillRect(0, 0, canvas.width, canvas.height);
  const frame = mapFrame(canvas, bounds || worldBounds(world, points));
  const { px, min, max } = frame;
  g.strokeStyle = '#2a2f36'; g.lineWidth = 1;
  for (let x = Math.floor(min[0]); x <= max[0]; ++x) { const [a] = px(x, 0); g.beginPath(); g.moveTo(a, 0); g.lineTo(a, canvas.height); g.stroke(); }
  for (let y = Math.floor(min[1]); y <= max[1]; ++y) { const [, b] = px(0, y); g.beginPath(); g.moveTo(0, b); g.lineTo(canvas.width, b); g.stroke(); }
  for (const r of world.regions) {
    const [x0, y0] = px(r.min[0], r.max[1]), [x1, y1] = px(r.max[0], r.min[1]);
    g.fillStyle = 'rgba(46,160,67,0.25)'; g.fillRect(x0, y0, x1 - x0, y1 - y0);
    g.fillStyle = '#7ee787'; g.font = '10px sans-serif'; g.fillText(r.name, x0 + 2, y0 + 10);
  }
  for (const b of world.boxes) drawBox(g, frame, b.center, b.size, b.yaw, MAP_FILLS[b.kind] || MAP_FILLS.prop);
  return frame;
}
