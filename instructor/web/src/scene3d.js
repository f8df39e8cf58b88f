// The 3D scene both the console and the trainee page draw: the world of
// /api/world as boxes (walls, doors on their hinges, stairs, props, regions,
// movable objects), the robot as its chassis box, and the onboard camera
// placed from RobotState's base pose and the robot file's camera mount.
import * as THREE from 'three';
import { ROBOT_COLOUR } from './common.js';
import { robotTree, poseTree } from './robot_tree.js';

const KIND_COLOURS = { wall: 0xc9c9c9, door: 0x8b4513, stairs: 0x5c7cfa, box: 0x8d8d8d, prop: 0x9775fa };
// How far an open door is drawn swung: RobotState carries no door angles,
// only the SimEvents door_opened / door_closed say which doors stand open
// (and the robot's heading says which way it went).
const DOOR_OPEN_RAD = 80 * Math.PI / 180;

// Whether WebGL runs in software (SwiftShader, llvmpipe: a machine without a
// GPU), asked of a throwaway context.
export function softwareWebGL() {
  const gl = document.createElement('canvas').getContext('webgl2') || document.createElement('canvas').getContext('webgl');
  const info = gl && gl.getExtension('WEBGL_debug_renderer_info');
  return !!info && /swiftshader|llvmpipe|software/i.test(gl.getParameter(info.UNMASKED_RENDERER_WEBGL));
}

// A renderer on `canvas` and a lit, sky-coloured scene. preserveDrawingBuffer:
// the tests read the pixels back.
export function createView(canvas, antialias = true) {
  const renderer = new THREE.WebGLRenderer({ canvas, antialias, preserveDrawingBuffer: true });
  renderer.setSize(canvas.width, canvas.height, false);
  renderer.setScissorTest(true);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x87a8c8);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x444444, 2.0));
  const sun = new THREE.DirectionalLight(0xffffff, 1.5); sun.position.set(5, -3, 10); scene.add(sun);
  return { renderer, scene };
}

// A camera with z up (the world frame).
export function camera(fov, aspect) {
  const c = new THREE.PerspectiveCamera(fov, aspect, 0.05, 200);
  c.up.set(0, 0, 1);
  return c;
}

function doorPivot(b) {
  // The door panel runs from its hinge along its yaw (world_json draws it closed).
  const pivot = new THREE.Group();
  const half = b.size[0] / 2;
  pivot.position.set(b.center[0] - half * Math.cos(b.yaw), b.center[1] - half * Math.sin(b.yaw), 0);
  pivot.rotation.z = b.yaw;
  const m = new THREE.Mesh(new THREE.BoxGeometry(...b.size), new THREE.MeshLambertMaterial({ color: KIND_COLOURS.door }));
  m.position.set(half, 0, b.center[2]);
  pivot.add(m);
  pivot.userData.yaw = b.yaw;
  return pivot;
}

// Adds the world to `scene`; returns the movable parts: objects (by name) and doors (by name).
export function buildWorld(scene, world) {
  const ground = new THREE.Mesh(new THREE.PlaneGeometry(200, 200), new THREE.MeshLambertMaterial({ color: 0x5b6b4a }));
  scene.add(ground);
  const grid = new THREE.GridHelper(100, 100, 0x333333, 0x444444); grid.rotation.x = Math.PI / 2; grid.position.z = 0.01;
  scene.add(grid);
  const doors = new Map(), objects = new Map();
  for (const b of world.boxes) {
    if (b.kind === 'door') { const d = doorPivot(b); scene.add(d); doors.set(b.name, d); continue; }
    const m = new THREE.Mesh(new THREE.BoxGeometry(...b.size), new THREE.MeshLambertMaterial({ color: KIND_COLOURS[b.kind] || KIND_COLOURS.prop }));
    m.position.set(...b.center); m.rotation.z = b.yaw;
    scene.add(m);
  }
  for (const r of world.regions) {
    const size = [0, 1, 2].map((i) => Math.max(0.01, r.max[i] - r.min[i]));
    const m = new THREE.Mesh(new THREE.BoxGeometry(...size),
      new THREE.MeshBasicMaterial({ color: 0x2ea043, transparent: true, opacity: 0.2, depthWrite: false }));
    m.position.set(...[0, 1, 2].map((i) => (r.max[i] + r.min[i]) / 2));
    scene.add(m);
  }
  for (const o of world.objects) {
    const m = new THREE.Mesh(new THREE.BoxGeometry(...o.size), new THREE.MeshLambertMaterial({ color: 0xe3b341 }));
    m.position.set(...o.center); scene.add(m); objects.set(o.name, m);
  }
  return { objects, doors };
}

// A door drawn open or closed (from the SimEvents door_opened / door_closed),
// swung the way the robot (`robotState`, the one that pushed it) drives, or,
// while it stands, away from it.
export function setDoorOpen(doors, name, open, robotState) {
  const d = doors.get(name);
  if (!d) return;
  const yaw = d.userData.yaw, r = robotState;
  // A positive turn swings the door's free end towards the normal n = (-sin yaw, cos yaw).
  const n = [-Math.sin(yaw), Math.cos(yaw)];
  let toward = 1;
  if (r && Math.abs(r.speed_mps) > 0.05) toward = Math.sign(r.speed_mps) * (Math.cos(r.yaw) * n[0] + Math.sin(r.yaw) * n[1]);
  else if (r) toward = -((r.position[0] - d.position.x) * n[0] + (r.position[1] - d.position.y) * n[1]);
  d.rotation.z = yaw + (open ? Math.sign(toward || 1) * DOOR_OPEN_RAD : 0);
}

// The movable objects at their positions in RobotState.
export function placeObjects(objects, robotState) {
  for (const o of robotState.objects) { const m = objects.get(o.name); if (m) m.position.set(...o.position); }
}

// The robot: its chassis box (unlit, so that its colour reaches the screen as
// it is: the tests look for it) with a dark nose.
// A urdf_tree robot file draws its links' visual shapes instead.
export function robotMesh(world) {
  if (world.robot && world.robot.links) return robotTree(world.robot);
  const g = new THREE.Group();
  const size = (world.robot && world.robot.chassis_size) || [0.8, 0.5, 0.25];
  g.add(new THREE.Mesh(new THREE.BoxGeometry(...size), new THREE.MeshBasicMaterial({ color: ROBOT_COLOUR })));
  const nose = new THREE.Mesh(new THREE.BoxGeometry(0.15, size[1] / 2, 0.08), new THREE.MeshLambertMaterial({ color: 0x222222 }));
  nose.position.set(size[0] / 2 - 0.08, 0, size[2] / 2 + 0.04); g.add(nose);
  return g;
}

export function poseRobot(group, robotState) {
  const q = robotState.orientation_wxyz;
  group.position.set(...robotState.position);
  group.quaternion.set(q[1], q[2], q[3], q[0]);
  poseTree(group, robotState);
}

// The onboard camera: the robot file's first camera mount (`sensors.cameras`,
// base frame, x forward, z up, rpy; e.g. skid4's "front" 0.41 m ahead, 10°
// down), or without a robot file 0.30 m ahead and 0.50 m above the base,
// 10° down.
export function onboardMount(world) {
  const c = world.robot && world.robot.cameras && world.robot.cameras[0];
  return c ? { name: c.name, position: c.position, rpy: c.rpy } : { name: 'onboard', position: [0.30, 0, 0.50], rpy: [0, 10 * Math.PI / 180, 0] };
}

// Places `cam` at the mount of a robot posed as `robotGroup` (poseRobot).
export function placeOnboard(cam, mount, robotGroup) {
  const q = robotGroup.quaternion;
  const at = new THREE.Vector3(...mount.position).applyQuaternion(q).add(robotGroup.position);
  cam.position.copy(at);
  // The mount's x axis, R = Rz(yaw) Ry(pitch) Rx(roll), in the world.
  const [, p, y] = mount.rpy;
  const dir = new THREE.Vector3(Math.cos(p) * Math.cos(y), Math.cos(p) * Math.sin(y), -Math.sin(p)).applyQuaternion(q);
  cam.lookAt(at.clone().add(dir));
}

// A third-person camera behind and above `pos` (a Vector3), looking at it.
export function placeChase(cam, pos, yaw, back = 4.0, up = 2.5) {
  cam.position.set(pos.x - back * Math.cos(yaw), pos.y - back * Math.sin(yaw), pos.z + up);
  cam.lookAt(pos);
}

// Whether the robot's RobotState.active_faults ("id: camera_blackout
// target", target "" = every camera) blacks out the camera `name`.
export function cameraBlackedOut(robotState, name) {
  return (robotState.active_faults || []).some((f) => {
    const m = /^[^:]*: camera_blackout ?(.*)$/.exec(f);
    return m && (m[1].trim() === '' || m[1].trim() === name);
  });
}

// Draws `cam`'s picture into the canvas rectangle r (pixels, y up as WebGL's
// viewport), or black when the camera is blacked out.
export function renderInto(renderer, scene, cam, r, black = false) {
  renderer.setViewport(r.x, r.y, r.w, r.h); renderer.setScissor(r.x, r.y, r.w, r.h);
  if (black) { renderer.setClearColor(0x000000, 1); renderer.clear(); return; }
  renderer.render(scene, cam);
}

// Pixel statistics of a canvas for the browser tests: the luminance's mean
// and variance, and how many pixels carry the robot's colour.
export function canvasStats(canvas) {
  const c = document.createElement('canvas'); c.width = canvas.width; c.height = canvas.height;
  const g = c.getContext('2d'); g.drawImage(canvas, 0, 0);
  const d = g.getImageData(0, 0, c.width, c.height).data;
  const want = [(ROBOT_COLOUR >> 16) & 255, (ROBOT_COLOUR >> 8) & 255, ROBOT_COLOUR & 255];
  let sum = 0, sum2 = 0, robot = 0; const n = d.length / 4;
  for (let i = 0; i < d.length; i += 4) {
    const y = 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2]; sum += y; sum2 += y * y;
    if (Math.abs(d[i] - want[0]) <= 12 && Math.abs(d[i + 1] - want[1]) <= 12 && Math.abs(d[i + 2] - want[2]) <= 12) robot++;
  }
  const mean = sum / n;
  return { mean, variance: sum2 / n - mean * mean, robot_pixels: robot, pixels: n };
}
