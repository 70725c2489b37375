#pragma once
// Vulkan compute without sound knowledge, after Kompute's split. Entry points:
//   open_device, Context   the device choice (cpu, gpu, auto) and the logical device
//   Buffer                 device memory with staging
//   Pipeline               an embedded SPIR-V kernel with push and specialization constants
//   Sequence               recorded commands, fences and timestamps
#include "chladni/gpu/buffer.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/gpu/pipeline.hpp"
#include "chladni/gpu/sequence.hpp"
