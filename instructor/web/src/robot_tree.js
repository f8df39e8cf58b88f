// A urdf_tree robot (/api/world's robot.links and robot.joints, from
// instructor/web_json.cpp robot_json) as three.js groups: one per link, each
// hung under its joint's origin in its parent link; posed by the joint
// positions of RobotState (rad, m), as URDF turns and slides them.
import * as THREE from 'three';

function setPose(obj, p) {
  obj.position.set(...p.xyz);
  obj.quaternion.set(p.wxyz[1], p.wxyz[2], p.wxyz[3], p.wxyz[0]);
}

// A visual shape in its link's frame: a primitive, or a mesh's flat arrays.
function visualMesh(v, material) {
  let geometry;
  if (v.type === 'box') geometry = new THREE.BoxGeometry(...v.size);
  else if (v.type === 'sphere') geometry = new THREE.SphereGeometry(v.size[0], 16, 12);
  else if (v.type === 'cylinder') {
    geometry = new THREE.CylinderGeometry(v.size[0], v.size[0], v.size[1], 24);
    geometry.rotateX(Math.PI / 2);  // three.js cylinders stand along y, URDF's along z
  } else {
    geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.Float32BufferAttribute(v.vertices, 3));
    geometry.setIndex(v.triangles);
    geometry.computeVertexNormals();
  }
  const mesh = new THREE.Mesh(geometry, material);
  setPose(mesh, v.origin);
  return mesh;
}

// The robot's link tree; its root link's frame is the base frame RobotState poses.
export function robotTree(robot) {
  const root = new THREE.Group();
  const links = robot.links.map((l) => {
    const g = new THREE.Group();
    g.name = l.name;
    const material = new THREE.MeshLambertMaterial({ color: new THREE.Color(l.rgba[0], l.rgba[1], l.rgba[2]) });
    for (const v of l.visuals) g.add(visualMesh(v, material));
    return g;
  });
  root.add(links[0]);
  root.userData.joints = robot.joints.map((j) => {
    const frame = new THREE.Group();
    setPose(frame, j.origin);
    links[j.parent].add(frame);
    frame.add(links[j.child]);
    return { name: j.name, type: j.type, axis: new THREE.Vector3(...j.axis), link: links[j.child] };
  });
  return root;
}

// Turns and slides each moving joint's child link to RobotState's position
// (a joint RobotState does not name stays at 0).
export function poseTree(group, robotState) {
  const joints = group.userData.joints;
  if (!joints) return;
  const at = new Map((robotState.joints || []).map((j) => [j.name, j.position]));
  for (const j of joints) {
    const q = at.get(j.name) || 0;
    if (j.type === 'prismatic') j.link.position.copy(j.axis).multiplyScalar(q);
    else if (j.type !== 'fixed') j.link.quaternion.setFromAxisAngle(j.axis, q);
  }
}
