// The Vulkan compute layer on whatever device is present (lavapipe in CI).
#include <gtest/gtest.h>

#include <numeric>

#include "chladni/gpu/buffer.hpp"
#include "chladni/gpu/context.hpp"
#include "chladni/gpu/pipeline.hpp"
#include "chladni/gpu/sequence.hpp"
#include "chladni/kernels/reduce.spv.h"
#include "test_support.hpp"

using namespace chladni;

TEST(Gpu, DeviceLocalBufferRoundTripsThroughStaging) {
  CHLADNI_REQUIRE_GPU_OR_SKIP(ctx);
  std::vector<uint32_t> in(100000), out(100000);
  std::iota(in.begin(), in.end(), 7u);
  gpu::Buffer b(*ctx, in.size() * 4, gpu::Memory::DeviceLocal);
  EXPECT_FALSE(b.mapped());
  b.upload(in.data(), in.size() * 4);
  b.download(out.data(), out.size() * 4);
  EXPECT_EQ(in, out);
  uint32_t part[3];
  b.download(part, sizeof(part), 4 * 1000);
  EXPECT_EQ(part[0], 1007u);
  EXPECT_EQ(part[2], 1009u);
  b.zero();
  b.download(part, sizeof(part), 0);
  EXPECT_EQ(part[1], 0u);
  EXPECT_THROW(b.upload(in.data(), 8, in.size() * 4), gpu::Error);
}

TEST(Gpu, PipelineWithPushConstantsComputesAndTimestampsAdvance) {
  CHLADNI_REQUIRE_GPU_OR_SKIP(ctx);
  // reduce.comp: sums `rows` rows of `count` floats into the result buffer.
  const uint32_t rows = 50, count = 300;
  std::vector<float> data(rows * count);
  for (uint32_t r = 0; r < rows; ++r) {
    for (uint32_t i = 0; i < count; ++i) data[r * count + i] = float(r) + 0.001f * i;
  }
  gpu::Buffer scratch(*ctx, data.size() * 4, gpu::Memory::DeviceLocal);
  gpu::Buffer result(*ctx, count * 4, gpu::Memory::HostVisible);
  scratch.upload(data.data(), data.size() * 4);
  gpu::Pipeline p(*ctx, std::span(k_reduce_spv), 2, 24);
  p.bind(0, scratch);
  p.bind(1, result);
  gpu::Sequence seq(*ctx, 2);
  const uint32_t push[6] = {0, 0, rows, count, 64, 1};
  seq.begin();
  seq.timestamp(0);
  seq.dispatch(p, (count + 63) / 64, push, sizeof(push));
  seq.barrier();
  seq.timestamp(1);
  seq.run();
  const float* out = static_cast<const float*>(result.data());
  for (uint32_t i = 0; i < count; ++i) {
    EXPECT_NEAR(out[i], rows * (rows - 1) / 2.0 + rows * 0.001 * i, 1e-3) << i;
  }
  if (ctx->timestamps()) {
    EXPECT_GE(seq.elapsed_ns(0, 1), 0.0);
  }
  EXPECT_EQ(ctx->validation_errors(), 0u);
}

TEST(Gpu, UnknownDeviceSelectionIsAClearNoDeviceError) {
  CHLADNI_REQUIRE_GPU_OR_SKIP(ctx);
  gpu::ContextOptions o;
  o.device = "no-such-device-xyz";
  try {
    gpu::Context c(o);
    FAIL() << "expected NoDeviceError";
  } catch (const gpu::NoDeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-device-xyz"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find(ctx->info().name), std::string::npos);
  }
  o.device = "0";
  gpu::Context by_index(o);
  EXPECT_EQ(by_index.info().index, 0u);
}

TEST(Gpu, ListsDevicesWithTheirTypes) {
  CHLADNI_REQUIRE_GPU_OR_SKIP(ctx);
  const auto devices = gpu::Context::list_devices();
  ASSERT_FALSE(devices.empty());
  bool found = false;
  for (const auto& d : devices) found |= d.name == ctx->info().name;
  EXPECT_TRUE(found);
  EXPECT_GE(ctx->subgroup_size(), 1u);
}
