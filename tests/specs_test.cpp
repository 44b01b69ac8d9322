// The command line's spec languages (cli/specs): every mistake is a UsageError naming the option.
#include "cli/specs.h"

#include <gtest/gtest.h>

#include "prtsub/subdiv/exceptions.h"

namespace prtsub {
namespace {

TEST(Specs, LightSpecsParseAndBadSpecsAreUsageErrorsNamingTheOption) {
  EXPECT_EQ(parse_light("sh:1,2", 3).coeffs(1, 1), 2.0);
  EXPECT_EQ(parse_light("sh:1,2", 3).coeffs(2, 0), 0.0);
  EXPECT_NO_THROW(parse_light("sun:0,1,0", 4));
  EXPECT_NO_THROW(parse_light("sun:0,1,0,2", 4));
  EXPECT_NO_THROW(parse_light("sky", 4));
  EXPECT_NO_THROW(parse_light("sky:0,0,1", 4));
  EXPECT_NO_THROW(parse_light("random:3", 4));
  for (const char* bad : {"sun:0,0,0", "sun:1,2", "sh:1,x", "sh:1,2,3,4,5", "moon:1", "random:-1", "env:", "sky:1"}) {
    try {
      parse_light(bad, 2);
      ADD_FAILURE() << bad;
    } catch (const UsageError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(std::string("--light ") + bad + ":", 0), 0u) << e.what();
    }
  }
  EXPECT_THROW(parse_light("env:/no/such/map.exr", 2), IoError);
  Eigen::Matrix3d R = parse_rotation("y,90");
  EXPECT_LT((R * Eigen::Vector3d::UnitX() - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  EXPECT_LT((parse_rotation("0,0,2,90") * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 1e-12);
  EXPECT_THROW(parse_rotation("q,3"), UsageError);
  EXPECT_THROW(parse_rotation("x"), UsageError);
}

TEST(Specs, CameraSpecsParseAndBadOnesNameTheOption) {
  Camera p = parse_camera("eye=1,2,3:target=0,0,0:up=0,0,1:fov=30");
  EXPECT_EQ(p.eye, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(p.up, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(p.fov_deg, 30);
  for (const char* bad : {"eye=0,0,0:target=0,0,0", "eye=0,0,1:target=0,0,0:up=0,0,1", "eye=0,0,1", "eye=1,1,1",
                          "eye=1,2:target=0,0,0", "eye=1,1,1:target=0,0,0:fov=180", "eye=1,1,1:target=0,0,0:zoom=2", "nonsense"}) {
    try {
      parse_camera(bad);
      ADD_FAILURE() << bad;
    } catch (const UsageError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("--camera", 0), 0u) << e.what();
    }
  }
}

}  // namespace
}  // namespace prtsub
