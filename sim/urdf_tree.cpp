#include "sim/urdf_tree.hpp"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Dense>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "sim/urdf_model.hpp"

namespace rise::sim {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what); }

/// liburdfdom logs through console_bridge: collect its messages instead of
/// printing them (libraries do not print). console_bridge's handler is
/// process-wide, so robot files are loaded from one thread at a time.
class CapturedLog : public console_bridge::OutputHandler {
 public:
  CapturedLog() { console_bridge::useOutputHandler(this); }
  ~CapturedLog() override { console_bridge::restorePreviousOutputHandler(); }
  CapturedLog(const CapturedLog&) = delete;
  CapturedLog& operator=(const CapturedLog&) = delete;

  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level < console_bridge::CONSOLE_BRIDGE_LOG_ERROR) return;
    errors_ += (errors_.empty() ? "" : "; ") + text;
  }
  const std::string& errors() const { return errors_; }

 private:
  std::string errors_;
};

// Whether `text` is whole UTF-8 sequences: tinyxml 2.6 (liburdfdom's XML
// parser) takes a lead byte's length on trust and reads past the end of a
// text cut inside a sequence (a heap overflow found by the urdf fuzz target).
bool whole_utf8(const std::string& text) {
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    const std::size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    if (n == 0 || n > text.size() - i) return false;
    for (std::size_t k = 1; k < n; ++k)
      if ((static_cast<unsigned char>(text[i + k]) & 0xC0) != 0x80) return false;
    i += n;
  }
  return true;
}

bool finite(const urdf::Vector3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

UrdfPose pose_of(const urdf::Pose& p, const std::string& what) {
  const auto& q = p.rotation;
  if (!finite(p.position) || !(std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z)))
    fail(what + ": origin is not finite");
  Eigen::Quaterniond e(q.w, q.x, q.y, q.z);
  if (!(e.norm() > 0.5)) fail(what + ": origin rotation is not a rotation");
  e.normalize();
  return UrdfPose{{p.position.x, p.position.y, p.position.z}, {e.w(), e.x(), e.y(), e.z()}};
}

bool positive(double v) { return std::isfinite(v) && v > 0; }

UrdfShape shape_of(const urdf::Geometry& g, const urdf::Pose& origin, const std::string& what,
                   const std::string& mesh_dir, bool load_meshes) {
  UrdfShape s;
  s.origin = pose_of(origin, what);
  switch (g.type) {
    case urdf::Geometry::BOX: {
      const auto& d = static_cast<const urdf::Box&>(g).dim;
      s.type = UrdfShapeType::Box;
      s.size_m = {d.x, d.y, d.z};
      break;
    }
    case urdf::Geometry::CYLINDER: {
      const auto& c = static_cast<const urdf::Cylinder&>(g);
      s.type = UrdfShapeType::Cylinder;
      s.size_m = {c.radius, c.length, 1.0};
      break;
    }
    case urdf::Geometry::SPHERE: {
      s.type = UrdfShapeType::Sphere;
      s.size_m = {static_cast<const urdf::Sphere&>(g).radius, 1.0, 1.0};
      break;
    }
    case urdf::Geometry::MESH: {
      const auto& m = static_cast<const urdf::Mesh&>(g);
      s.type = UrdfShapeType::Mesh;
      s.mesh_file = m.filename;
      s.mesh_scale = {m.scale.x, m.scale.y, m.scale.z};
      s.size_m = {1.0, 1.0, 1.0};
      for (double k : s.mesh_scale)
        if (!(std::isfinite(k) && k != 0.0)) fail(what + ": mesh scale must be finite and not 0");
      if (s.mesh_file.rfind("package://", 0) == 0)
        fail(what + ": mesh '" + s.mesh_file + "': package:// needs a ROS package path; give a path relative to the URDF");
      if (load_meshes) {
        std::string file = s.mesh_file.rfind("file://", 0) == 0 ? s.mesh_file.substr(7) : s.mesh_file;
        const std::filesystem::path path = std::filesystem::path(file).is_absolute()
                                               ? std::filesystem::path(file)
                                               : std::filesystem::path(mesh_dir) / file;
        s.mesh = read_mesh_file(path.string(), s.mesh_scale);
      }
      break;
    }
    default: fail(what + ": unknown geometry");
  }
  for (double v : s.size_m)
    if (!positive(v)) fail(what + ": sizes must be > 0");
  return s;
}

UrdfLink link_of(const urdf::Link& l, const std::string& mesh_dir, bool load_meshes) {
  UrdfLink out;
  out.name = l.name;
  if (l.inertial) {
    const urdf::Inertial& i = *l.inertial;
    const std::string what = "link '" + l.name + "' inertial";
    if (!positive(i.mass)) fail(what + ": mass must be > 0");
    out.mass_kg = i.mass;
    out.inertial_origin = pose_of(i.origin, what);
    out.inertia_kgm2 = {i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz};
    Eigen::Matrix3d I;
    I << i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz;
    if (!I.allFinite()) fail(what + ": inertia is not finite");
    // ODE needs a positive definite inertia whose principal moments meet the
    // triangle inequality (any rigid body's do).
    const Eigen::Vector3d m = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(I, Eigen::EigenvaluesOnly).eigenvalues();
    if (!(m[0] > 0) || m[0] + m[1] < m[2] * (1 - 1e-6))
      fail(what + ": inertia is not a rigid body's (positive definite, each principal moment <= the sum of the others)");
  }
  for (std::size_t k = 0; k < l.collision_array.size(); ++k) {
    const auto& c = l.collision_array[k];
    const std::string what = "link '" + l.name + "' collision " + std::to_string(k);
    if (!c || !c->geometry) fail(what + ": no geometry");
    out.collisions.push_back(shape_of(*c->geometry, c->origin, what, mesh_dir, load_meshes));
  }
  for (std::size_t k = 0; k < l.visual_array.size(); ++k) {
    const auto& v = l.visual_array[k];
    const std::string what = "link '" + l.name + "' visual " + std::to_string(k);
    if (!v || !v->geometry) fail(what + ": no geometry");
    out.visuals.push_back(shape_of(*v->geometry, v->origin, what, mesh_dir, load_meshes));
    if (k == 0 && v->material) {
      const auto& c = v->material->color;
      out.rgba = {c.r, c.g, c.b, c.a};
    }
  }
  return out;
}

UrdfJoint joint_of(const urdf::Joint& j) {
  UrdfJoint out;
  out.name = j.name;
  const std::string what = "joint '" + j.name + "'";
  switch (j.type) {
    case urdf::Joint::REVOLUTE: out.type = UrdfJointType::Revolute; break;
    case urdf::Joint::CONTINUOUS: out.type = UrdfJointType::Continuous; break;
    case urdf::Joint::PRISMATIC: out.type = UrdfJointType::Prismatic; break;
    case urdf::Joint::FIXED: out.type = UrdfJointType::Fixed; break;
    default: fail(what + ": unsupported type (revolute, continuous, prismatic or fixed)");
  }
  out.origin = pose_of(j.parent_to_joint_origin_transform, what);
  if (out.type == UrdfJointType::Fixed) return out;
  Eigen::Vector3d axis(j.axis.x, j.axis.y, j.axis.z);
  if (!axis.allFinite() || !(axis.norm() > 1e-9)) fail(what + ": axis must be a finite, non-zero vector");
  axis.normalize();
  out.axis = {axis.x(), axis.y(), axis.z()};
  if (j.limits) {
    const auto& l = *j.limits;
    if (out.type != UrdfJointType::Continuous) {
      if (!(std::isfinite(l.lower) && std::isfinite(l.upper) && l.lower <= l.upper))
        fail(what + ": limit lower must be <= upper");
      out.lower = l.lower;
      out.upper = l.upper;
    }
    if (!(std::isfinite(l.effort) && l.effort >= 0)) fail(what + ": limit effort must be >= 0");
    if (!(std::isfinite(l.velocity) && l.velocity >= 0)) fail(what + ": limit velocity must be >= 0");
    out.effort = l.effort;
    out.velocity = l.velocity;
  }
  if (j.dynamics) {
    if (!(std::isfinite(j.dynamics->damping) && j.dynamics->damping >= 0)) fail(what + ": damping must be >= 0");
    if (!(std::isfinite(j.dynamics->friction) && j.dynamics->friction >= 0)) fail(what + ": friction must be >= 0");
    out.damping = j.dynamics->damping;
    out.friction = j.dynamics->friction;
  }
  return out;
}

// Depth first from the root, so that a parent always comes before its child.
void add_subtree(const urdf::Link& l, std::size_t index, const std::string& mesh_dir, bool load_meshes,
                 UrdfTree& tree) {
  for (const auto& j : l.child_joints) {
    if (!j) continue;
    urdf::LinkConstSharedPtr c;
    for (const auto& cl : l.child_links)
      if (cl && cl->name == j->child_link_name) c = cl;
    if (!c) fail("joint '" + j->name + "': no child link '" + j->child_link_name + "'");
    if (tree.links.size() >= kMaxUrdfLinks) fail("more than " + std::to_string(kMaxUrdfLinks) + " links");
    UrdfJoint joint = joint_of(*j);
    joint.parent = index;
    joint.child = tree.links.size();
    UrdfLink link = link_of(*c, mesh_dir, load_meshes);
    if (joint.type != UrdfJointType::Fixed && link.mass_kg == 0.0)
      fail("link '" + link.name + "' moves on joint '" + joint.name + "' and needs an inertial with a mass");
    tree.links.push_back(std::move(link));
    tree.joints.push_back(joint);
    add_subtree(*c, joint.child, mesh_dir, load_meshes, tree);
  }
}

}  // namespace

urdf::ModelInterfaceSharedPtr parse_urdf_model(const std::string& xml) {
  if (!whole_utf8(xml)) fail("not UTF-8 text");
  urdf::ModelInterfaceSharedPtr model;
  std::string errors;
  {
    CapturedLog log;
    try {
      model = urdf::parseURDF(xml);
    } catch (const std::exception& e) {
      fail(std::string("liburdfdom: ") + e.what());
    }
    errors = log.errors();
  }
  // liburdfdom drops an element it cannot read and goes on: its logged error is the refusal.
  if (!model || !errors.empty()) fail("liburdfdom: " + (errors.empty() ? std::string("cannot parse") : errors));
  if (!model->getRoot()) fail("no root link");
  return model;
}

std::size_t UrdfTree::joint_index(const std::string& name) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == name) return i;
  return joints.size();
}

std::size_t UrdfTree::body_link(std::size_t link) const {
  while (link > 0 && joints[link - 1].type == UrdfJointType::Fixed) link = joints[link - 1].parent;
  return link;
}

std::size_t UrdfTree::link_index(const std::string& name) const {
  for (std::size_t i = 0; i < links.size(); ++i)
    if (links[i].name == name) return i;
  return links.size();
}

UrdfTree parse_urdf_tree(const std::string& xml, const std::string& mesh_dir, bool load_meshes) {
  const urdf::ModelInterfaceSharedPtr model = parse_urdf_model(xml);
  const auto root = model->getRoot();
  UrdfTree tree;
  tree.links.push_back(link_of(*root, mesh_dir, load_meshes));
  add_subtree(*root, 0, mesh_dir, load_meshes, tree);
  // Links held by fixed joints share one body: each body needs a mass.
  std::vector<double> body_mass(tree.links.size(), 0.0);
  for (std::size_t l = 0; l < tree.links.size(); ++l) body_mass[tree.body_link(l)] += tree.links[l].mass_kg;
  for (std::size_t l = 0; l < tree.links.size(); ++l)
    if (tree.body_link(l) == l && !(body_mass[l] > 0))
      fail("link '" + tree.links[l].name + "' and the links fixed to it need an inertial with a mass");
  return tree;
}

UrdfTree read_urdf_tree(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  return parse_urdf_tree(text.str(), std::filesystem::path(path).parent_path().string(), true);
}

}  // namespace rise::sim
