// The world drawn top-down on a 2D canvas (x to the right, y up): the grid,
// the regions, the walls/doors/stairs/props and the objects. The console's
// live map and the builder pages draw through it; `view` converts between
// metres and canvas pixels both ways (the builders place things by mouse).

export const BOX_FILLS = { wall: '#8b949e', door: '#a0522d', stairs: '#4c6ef5', box: '#6e7681', prop: '#6e5494' };
export const OBJECT_FILL = '#e3b341';

// The world's extent in metres, grown by `points` ([[x, y], ...]) and 3 m
// around the robot's start.
export function worldBounds(world, points = []) {
  let min = [Infinity, Infinity], max = [-Infinity, -Infinity];
  const grow = (x, y) => { min = [Math.min(min[0], x), Math.min(min[1], y)]; max = [Math.max(max[0], x), Math.max(max[1], y)]; };
  for (const b of world.boxes) {
    // The turned box's own extent (a long wall's circle would add metres of nothing).
    const c = Math.abs(Math.cos(b.yaw || 0)), s = Math.abs(Math.sin(b.yaw || 0));
    const hx = (c * b.size[0] + s * b.size[1]) / 2, hy = (s * b.size[0] + c * b.size[1]) / 2;
    grow(b.center[0] - hx, b.center[1] - hy); grow(b.center[0] + hx, b.center[1] + hy);
  }
  for (const r of world.regions) { grow(r.min[0], r.min[1]); grow(r.max[0], r.max[1]); }
  for (const p of points) grow(p[0], p[1]);
  grow(world.robot_start[0] - 3, world.robot_start[1] - 3);
  grow(world.robot_start[0] + 3, world.robot_start[1] + 3);
  return { min, max };
}

// The scale of `canvas` for `bounds`: px(x, y) → [u, v] pixels, metres(u, v) → [x, y].
export function mapView(canvas, { min, max }, margin = 0.5) {
  const s = Math.min(canvas.width / (max[0] - min[0] + 2 * margin), canvas.height / (max[1] - min[1] + 2 * margin));
  return {
    s,
    min,
    max,
    px: (x, y) => [(x - min[0] + margin) * s, canvas.height - (y - min[1] + margin) * s],
    metres: (u, v) => [u / s + min[0] - margin, (canvas.height - v) / s + min[1] - margin],
  };
}

// A box of `size` (m) at `center`, turned by `yaw` (rad).
export function drawBox(g, view, center, size, yaw, fill) {
  g.save();
  const [cx, cy] = view.px(center[0], center[1]);
  g.translate(cx, cy); g.rotate(-yaw);
  g.fillStyle = fill; g.fillRect(-size[0] * view.s / 2, -size[1] * view.s / 2, size[0] * view.s, size[1] * view.s);
  g.restore();
}

// An axis-aligned region: translucent green with its name.
export function drawRegion(g, view, r, fill = 'rgba(46,160,67,0.25)', label = '#7ee787') {
  const [x0, y0] = view.px(r.min[0], r.max[1]), [x1, y1] = view.px(r.max[0], r.min[1]);
  g.fillStyle = fill; g.fillRect(x0, y0, x1 - x0, y1 - y0);
  g.fillStyle = label; g.font = '10px sans-serif'; g.fillText(r.name, x0 + 2, y0 + 10);
}

// Background, 1 m grid, the world's regions and its static boxes.
export function drawWorld(g, view, world) {
  const c = g.canvas;
  g.fillStyle = '#101215'; g.fillRect(0, 0, c.width, c.height);
  g.strokeStyle = '#2a2f36'; g.lineWidth = 1;
  for (let x = Math.floor(view.min[0]); x <= view.max[0]; ++x) {
    const [a] = view.px(x, 0); g.beginPath(); g.moveTo(a, 0); g.lineTo(a, c.height); g.stroke();
  }
  for (let y = Math.floor(view.min[1]); y <= view.max[1]; ++y) {
    const [, b] = view.px(0, y); g.beginPath(); g.moveTo(0, b); g.lineTo(c.width, b); g.stroke();
  }
  for (const r of world.regions) drawRegion(g, view, r);
  for (const b of world.boxes) drawBox(g, view, b.center, b.size, b.yaw, BOX_FILLS[b.kind] || BOX_FILLS.prop);
}

// The world's objects at `positions` ([{name, position}]; default: where the world puts them).
export function drawObjects(g, view, world, positions) {
  const objects = positions || world.objects.map((o) => ({ name: o.name, position: o.center }));
  for (const o of objects) {
    const w = world.objects.find((x) => x.name === o.name);
    drawBox(g, view, o.position, w ? w.size : [0.3, 0.3, 0.3], 0, OBJECT_FILL);
  }
}

// A robot's footprint at `position` facing `yaw`, with a heading line and a label.
export function drawRobot(g, view, position, yaw, colour, label = '') {
  drawBox(g, view, position, [0.8, 0.6], yaw, colour);
  const [x, y] = view.px(position[0], position[1]);
  g.strokeStyle = '#fff'; g.lineWidth = 2; g.beginPath(); g.moveTo(x, y);
  g.lineTo(x + Math.cos(yaw) * 0.6 * view.s, y - Math.sin(yaw) * 0.6 * view.s); g.stroke();
  if (label) { g.fillStyle = '#fff'; g.font = '11px sans-serif'; g.fillText(label, x + 8, y - 8); }
}
