#include <gtest/gtest.h>

#include <thread>

#include "common/camera_buffer.hpp"

using namespace occ;
using namespace std::chrono_literals;

namespace {
NumberedCamera cam(uint32_t n) {
  NumberedCamera c;
  c.number = n;
  c.camera.eye = {double(n), 0, 0};
  return c;
}
}  // namespace

TEST(CameraBuffer, LockstepWaitsForTheExpectedNumber) {
  CameraBuffer b;
  std::thread t([&] {
    for (uint32_t i = 0; i < 5; ++i) {
      std::this_thread::sleep_for(2ms);
      b.put(cam(i));
    }
  });
  std::string why;
  auto c = b.take(3, 5s, &why);
  t.join();
  ASSERT_TRUE(c) << why;
  EXPECT_EQ(c->number, 3u);
  EXPECT_EQ(c->camera.eye.x, 3.0);
  EXPECT_TRUE(b.take(4, 1s, &why));
  EXPECT_FALSE(b.take(2, 10ms, &why));  // older ones were dropped
  EXPECT_NE(why.find("timed out"), std::string::npos);
}

TEST(CameraBuffer, LatestReturnsTheNewestAtLeastMin) {
  CameraBuffer b;
  for (uint32_t i = 0; i < 10; ++i) b.put(cam(i));
  std::string why;
  auto c = b.take_latest(2, 1s, &why);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->number, 9u);
  EXPECT_FALSE(b.take_latest(10, 10ms, &why));
}

TEST(CameraBuffer, CloseWakesAWaiterWithTheReason) {
  CameraBuffer b;
  std::thread t([&] {
    std::this_thread::sleep_for(5ms);
    b.close("render client said bye: done");
  });
  std::string why;
  EXPECT_FALSE(b.take(0, 10s, &why));
  t.join();
  EXPECT_EQ(why, "render client said bye: done");
}
