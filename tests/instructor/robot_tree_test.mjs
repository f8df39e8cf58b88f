// A urdf_tree robot's links in the 3D view (instructor/web/src/robot_tree.js,
// the module scene3d.js draws them with), under node's test runner: each link
// hangs under its joint's origin, a revolute joint turns its child about the
// URDF axis and a prismatic one slides it, by RobotState's joint positions;
// a mesh visual becomes an indexed geometry of its triangles.
// usage: node --test tests/instructor/robot_tree_test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import * as THREE from '../../instructor/web/node_modules/three/build/three.module.js';
import { robotTree, poseTree } from '../../instructor/web/src/robot_tree.js';

const origin = (xyz, wxyz = [1, 0, 0, 0]) => ({ xyz, wxyz });
const robot = {
  links: [
    { name: 'base', rgba: [0.2, 0.2, 0.2, 1],
      visuals: [{ type: 'mesh', size: [1, 1, 1], origin: origin([0, 0, 0]), vertices: [0, 0, 0, 1, 0, 0, 0, 1, 0], triangles: [0, 1, 2] }] },
    { name: 'arm', rgba: [1, 0, 0, 1], visuals: [{ type: 'box', size: [1, 0.1, 0.1], origin: origin([0.5, 0, 0]) }] },
    { name: 'slider', rgba: [0, 1, 0, 1], visuals: [{ type: 'cylinder', size: [0.05, 0.2, 1], origin: origin([0, 0, 0]) }] },
  ],
  joints: [
    { name: 'pan', type: 'revolute', parent: 0, child: 1, origin: origin([0, 0, 0.5]), axis: [0, 0, 1] },
    { name: 'slide', type: 'prismatic', parent: 1, child: 2, origin: origin([1, 0, 0]), axis: [1, 0, 0] },
  ],
};

// Where the slider link's origin is in the robot's frame.
function sliderAt(group) {
  group.updateMatrixWorld(true);
  return group.getObjectByName('slider').getWorldPosition(new THREE.Vector3());
}

test('links hang under their joint origins at zero positions', () => {
  const g = robotTree(robot);
  const p = sliderAt(g);
  assert.deepEqual([p.x, p.y, p.z].map((v) => +v.toFixed(6)), [1, 0, 0.5]);
  const base = g.getObjectByName('base').children[0];
  assert.equal(base.geometry.index.count, 3);
  assert.equal(base.geometry.getAttribute('position').count, 3);
});

test('RobotState joint positions turn and slide the child links as URDF has it', () => {
  const g = robotTree(robot);
  poseTree(g, { joints: [{ name: 'pan', position: Math.PI / 2 }, { name: 'slide', position: 0.25 }] });
  const p = sliderAt(g);
  // Pan +90° about +z takes the arm's +x to +y; the slide adds 0.25 m along it.
  assert.deepEqual([p.x, p.y, p.z].map((v) => +v.toFixed(6)), [0, 1.25, 0.5]);
  poseTree(g, { joints: [] });  // absent: back to 0
  assert.deepEqual([sliderAt(g).x, sliderAt(g).y].map((v) => +v.toFixed(6)), [1, 0]);
});
