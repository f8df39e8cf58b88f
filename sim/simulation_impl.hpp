#pragma once

// The inside of a Simulation, private to its own files: the ODE world, the
// robots' bodies and what the steps have seen so far. Each section of the
// simulation works on this state from its own file:
//   simulation.cpp           construction, the order of a step, the accessors and snapshots
//   simulation_world.cpp     the world's geoms: static boxes, stairs, doors, movable objects
//   simulation_robots.cpp    the robots' bodies: skid-steer, tracked, the arm
//   simulation_contacts.cpp  the contact model: which geoms meet, their friction, track belts
//   simulation_drive.cpp     panel input to drive, arm and horn commands
//   simulation_joints.cpp    joint loads: the arm's efforts, breaking overloaded joints
//   simulation_events.cpp    the semantic events (collisions, doors, regions, stairs, ...)
//   simulation_sounds.cpp    the robot files' sound cues
//   simulation_faults.cpp    physics and sensor faults
//   simulation_sensors.cpp   odometry, IMU, ray casts and camera poses
// Only sim/simulation*.cpp include it.

#include <ode/ode.h>

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "sim/simulation.hpp"

namespace rise::sim {

struct Simulation::Impl {
  // Static: ground and everything that never moves; Door and Object are world
  // bodies; the rest belong to a robot.
  enum class GeomKind { Ground, Obstacle, Door, Object, Chassis, Wheel, Track, Arm };
  struct GeomInfo {
    GeomKind kind;
    std::string name;  ///< entity (world) or part (robot; "<id>/<part>" with several robots)
    int side = 0;      ///< tracks: 0 left, 1 right
    bool loose = false;  ///< a door off its broken hinge: it meets the floor too
    int robot = -1;    ///< robot parts: the robot's index
    double friction = -1.0;  ///< urdf_tree links: the robot file's μ (links.<name>.friction); -1: default
  };
  static bool is_static(GeomKind k) { return k == GeomKind::Ground || k == GeomKind::Obstacle; }
  static bool is_robot(GeomKind k) {
    return k == GeomKind::Chassis || k == GeomKind::Wheel || k == GeomKind::Track || k == GeomKind::Arm;
  }

  static constexpr std::array<const char*, 4> kWheelNames{"wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr"};
  static constexpr std::array<const char*, 2> kTrackNames{"track_left", "track_right"};

  // A breakable joint: its load is watched every step.
  struct Breakable {
    std::string owner;  // robot id or door name
    std::string name;
    dJointID joint = nullptr;
    dBodyID child = nullptr;
    bool child_is_body1 = false;
    dJointFeedback feedback{};
    double break_load_nm = 0.0;
    int break_steps = 1;
    int over_steps = 0;
    double damage = 0.0;  // added to the robot's damage when it breaks
    int robot = -1;       // the robot whose joint it is; -1: a door's hinge
    bool broken() const { return joint == nullptr; }
    double nominal_break_load_nm = -1.0;  // before a weak_joint fault; -1: never weakened
  };
  struct DoorBody {
    const Door* desc = nullptr;
    dBodyID body = nullptr;
    GeomInfo* info = nullptr;
    std::size_t hinge = 0;  // index in breakables
    bool open = false;
  };
  struct ObjectBody {
    const MovableObject* desc = nullptr;
    dBodyID body = nullptr;
    bool moved = false;
  };
  struct ArmJoint {
    dJointID joint = nullptr;  // also in breakables (null once broken)
    std::size_t breakable = 0;
    bool slider = false;
  };
  // One robot: its bodies, its panel, its sensors and its own event state.
  struct Robot {
    std::string id;
    RobotDescription desc;
    RobotStart start;
    dBodyID chassis = nullptr;
    std::array<dBodyID, 4> wheels{};
    std::array<dJointID, 4> hinges{};
    std::array<dJointFeedback, 4> feedback{};  // ODE holds pointers: a Robot never moves
    std::array<double, 2> track_speed_mps{};
    std::array<double, 2> track_travel_m{};
    std::vector<dBodyID> bodies;
    std::vector<ArmJoint> arm_joints;  // yaw, pitch, elbow, gripper; urdf_tree: its moving joints in URDF order
    // urdf_tree: per moving joint (parallel to arm_joints) its URDF joint and
    // its control (index into desc.control.joints, -1: none); per link its
    // body and the link frame in that body's frame.
    struct TreeJoint {
      std::size_t urdf = 0;
      int control = -1;
      bool continuous = false;
      double turned_rad = 0.0;  // continuous: ODE's angle (±π) unwrapped, step by step
      double last_rad = 0.0;
    };
    std::vector<TreeJoint> tree_joints;
    std::vector<dBodyID> link_bodies;
    std::vector<Eigen::Isometry3d> T_body_link;
    std::vector<dTriMeshDataID> trimeshes;  // destroyed with the world
    JointCommand joint_command;
    dBodyID finger = nullptr;
    std::vector<double> arm_efforts;
    std::set<std::string> touching;
    std::set<std::string> inside_regions;
    std::set<std::string> climbed;
    bool tipped = false;
    double damage = 0.0;
    ControlInput input;
    DriveCommand command;
    ArmCommand arm_command;
    std::optional<Odometry> odometry;
    std::optional<Imu> imu;
    bool button_cues = false;              // the robot file has `on: button` cues
    std::set<std::string> buttons_down;    // their buttons held in the last step
    std::vector<PhysicsFault> faults;      // injection order
    std::array<double, 2> drive_factor{1.0, 1.0};  // left, right: motor_failure 0, motor_weakness value
    std::array<double, 2> grip_factor{1.0, 1.0};   // track_slip
  };
  // Robot part (a) against a world entity or another robot's part (b).
  struct Touch {
    int robot_a = -1;
    int robot_b = -1;  // -1: a world entity
    double impact_mps = 0.0;  // the largest normal approach speed among its contacts this step
  };
  struct ActiveCollision {
    int64_t started = 0;    // step of the first contact
    int64_t last_seen = 0;  // step of the latest contact
    int robot_a = -1;
    int robot_b = -1;
  };
  using Pair = std::pair<std::string, std::string>;

  std::vector<std::unique_ptr<Robot>> robots;
  WorldDescription world_desc;
  dWorldID world = nullptr;
  dSpaceID space = nullptr;         // bodies: robots, doors, objects
  dSpaceID static_space = nullptr;  // ground, ceiling, boxes, props, walls, stairs
  dJointGroupID contacts = nullptr;
  std::vector<Breakable> breakables;  // addresses stay fixed after build (feedback pointers)
  std::vector<DoorBody> doors;
  std::vector<ObjectBody> objects;
  std::vector<std::unique_ptr<GeomInfo>> infos;
  std::map<Pair, Touch> seen;  // this step
  std::map<Pair, ActiveCollision> active;
  std::vector<SimEvent> events;
  std::vector<SoundCue> sounds;  // one-shots
  int64_t steps = 0;
  dGeomID ray = nullptr;  // in no space: the scanner's probe

  ~Impl();
  double time_s() const { return static_cast<double>(steps) * kStepS; }

  // simulation.cpp
  void build(std::vector<RobotSpec> specs);
  void add_robots(std::vector<RobotSpec> specs);
  void create_ode_world();
  void build_robot(Robot& r, int index);
  void step();
  static std::vector<WheelState> wheel_states(const Robot& r);
  std::vector<JointState> joint_states(const Robot& r) const;

  // simulation_world.cpp
  dGeomID add_geom(dGeomID g, GeomKind kind, const std::string& name, int side = 0, int robot = -1);
  void add_static_box(const std::string& name, double cx, double cy, double cz, double sx, double sy, double sz,
                      double yaw);
  void add_static_box(const BoxObstacle& b);
  void build_world();
  void build_stairs(const Stairs& s);
  void build_door(const Door& d);
  void build_object(const MovableObject& o);
  void apply_door_return_torques();

  // simulation_robots.cpp
  dGeomID add_part(dGeomID g, GeomKind kind, const Robot& r, int index, const std::string& part, int side = 0);
  void build_chassis(Robot& r, int index, double chassis_z);
  void build_skid_steer(Robot& r, int index);
  void build_tracked(Robot& r, int index);
  dBodyID link_body(Robot& r, int index, const std::string& name, double mass_kg, double sx, double sy, double sz,
                    const double pos[3], double pitch_up_rad);
  void add_arm_joint(Robot& r, int index, const std::string& name, dJointID j, dBodyID child, double break_nm);
  void build_arm(Robot& r, int index);
  static void place_robot(Robot& r);

  // simulation_tree.cpp
  void build_urdf_tree(Robot& r, int index);
  static void set_tree_joints(Robot& r);
  static void unwrap_tree_joints(Robot& r);
  static void lift_onto_ground(Robot& r, const std::vector<dGeomID>& geoms);

  // simulation_contacts.cpp
  static void near_callback(void* data, dGeomID a, dGeomID b);
  static bool may_touch(dGeomID a, dGeomID b, const GeomInfo& ia, const GeomInfo& ib);
  void collide(dGeomID a, dGeomID b);
  void record_touch(const GeomInfo& ia, const GeomInfo& ib, const dContact* contact, int n);
  void set_surface(dContact& contact, const GeomInfo& ia, const GeomInfo& ib, const Robot* owner,
                   const double forward[3]) const;

  // simulation_drive.cpp
  void apply_command(Robot& r);
  static void set_drive_speeds(Robot& r);
  static void set_arm_rates(Robot& r);
  void update_button_cues(Robot& r);

  // simulation_joints.cpp
  void check_breakables();
  void break_joint(Breakable& b, double load);
  void update_arm_efforts(Robot& r);

  // simulation_events.cpp
  void emit(SimEventKind kind, std::string a, std::string b = {}, std::string detail = {});
  void update_events();
  void update_collision_events();
  void update_door_events();
  void update_object_events();
  void update_robot_events(Robot& r);

  // simulation_sounds.cpp
  void cue(const Robot& r, SoundTrigger trigger, const std::string& detail, double impact_mps = 0.0,
           const std::string& button = {});
  void door_cue(const std::string& door, SoundTrigger trigger, const std::string& detail);
  static double sound_source_value(const Robot& r, SoundSource source);
  static std::vector<SoundCue> continuous_cues(const Robot& r, double time_s);

  // simulation_faults.cpp
  Breakable* find_breakable(std::size_t robot, const std::string& name);
  void apply_fault_effects();
  std::string set_fault(std::size_t robot, PhysicsFault f);
  std::size_t clear_fault(std::size_t robot, const std::string& id, const char* why);

  // simulation_sensors.cpp
  struct RayHit;
  static void ray_callback(void* data, dGeomID a, dGeomID b);
  double cast_ray_m(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range_m, std::size_t own_robot);
  static Eigen::Isometry3d T_world_base(const Robot& r);
  static std::array<double, 2> side_speeds_mps(const Robot& r);
  void update_sensors(Robot& r);
};

}  // namespace rise::sim
