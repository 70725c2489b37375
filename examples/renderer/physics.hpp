#pragma once
// The renderer example's physics: Bullet drops five sounding bodies (inline modes) onto a floor,
// one every 0.6 s, each spawned in the runtime as it is let go (while the audio plays); each new
// contact becomes an impact through the C API at the audio clock's time, and each body's pose a
// move.
#include <btBulletDynamicsCommon.h>

#include <cstdio>
#include <memory>
#include <vector>

#include "chladni/chladni.h"
#include "vulkan_window.hpp"

class Physics {
 public:
  struct Impact {
    double time;  // s on the runtime's clock, when posted
    int body;
    double impulse;  // N s
  };

  explicit Physics(chladni_runtime* rt);
  ~Physics();
  /// Steps the world at 240 Hz up to `seconds` (the audio clock), posting what happened.
  void advance_to(double seconds, FILE* log);
  /// The bodies and the floor seen from the front (x right, z up), in a w x h window.
  std::vector<Rect> rects(int w, int h) const;
  const std::vector<Impact>& impacts() const { return impacts_; }
  /// Takes the bodies out of the world (before the runtime goes).
  void clear();

 private:
  struct Body {
    chladni_bank bank{0};
    chladni_object object{0};  // from its release
    double release = 0;        // s
    std::unique_ptr<btCollisionShape> shape;
    std::unique_ptr<btDefaultMotionState> motion;
    std::unique_ptr<btRigidBody> rigid;
    float rgba[4];
  };
  void post(const btPersistentManifold* man, const btManifoldPoint& pt, double t, FILE* log);

  chladni_runtime* rt_;
  btDefaultCollisionConfiguration collision_;
  btCollisionDispatcher dispatcher_{&collision_};
  btDbvtBroadphase broadphase_;
  btSequentialImpulseConstraintSolver solver_;
  btDiscreteDynamicsWorld world_{&dispatcher_, &broadphase_, &solver_, &collision_};
  btStaticPlaneShape floor_shape_{btVector3(0, 0, 1), 0};
  btDefaultMotionState floor_motion_;
  btRigidBody floor_{btRigidBody::btRigidBodyConstructionInfo(0, &floor_motion_, &floor_shape_)};
  std::vector<Body> bodies_;
  std::vector<Impact> impacts_;
  long steps_ = 0;
  std::size_t released_ = 0;
};
