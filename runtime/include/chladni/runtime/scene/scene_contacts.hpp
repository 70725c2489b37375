#pragma once
// A scene's contact events made playable: each one's surface, and its trajectory as control
// points at output samples with each body's nearest surface point.
#include <cstdint>
#include <vector>

#include "chladni/core/scene.hpp"
#include "chladni/runtime/contact/contact_bank.hpp"
#include "chladni/runtime/modal/object_modes.hpp"

namespace chladni::runtime {

/// The preset named by `spec.surface` with its overrides; InputError when out of range.
Roughness resolve_roughness(const RoughnessSpec& spec);

struct SceneContact {
  Roughness roughness;
  std::vector<ContactPoint> points;  ///< one per trajectory sample
};

/// InputError naming the event's JSON path for an unknown surface, a roughness out of range, or
/// a point farther off an object's surface than a tenth of the object's size.
std::vector<SceneContact> scene_contacts(const Scene& scene,
                                         const std::vector<ObjectModes>& objects);

/// Filterbank slots the scene's contacts take: each one's bodies' modes.
uint32_t contact_slots(const Scene& scene, const std::vector<ObjectModes>& objects);

/// The most control points of one contact that fall in `frames` samples, plus room to
/// interpolate on either side: a ContactBank's max_points for this scene.
uint32_t contact_points_per_block(const Scene& scene, uint32_t frames);

}  // namespace chladni::runtime
