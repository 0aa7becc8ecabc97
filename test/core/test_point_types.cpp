// Field layout of the shared point types: names and types must match what rviz configs,
// velodyne_pointcloud (XYZIRT) and the evaluation expect.
#include <gtest/gtest.h>

#include <pcl/common/io.h>

#include "urban_detection/core/common/point_types.h"

namespace ud = urban_detection;

TEST(PointTypes, XyzirtFieldsMatchVelodynePointcloud) {
  std::vector<pcl::PCLPointField> fields;
  pcl::getFields<ud::PointXYZIRT>(fields);
  std::vector<std::string> names;
  for (const auto& f : fields) names.push_back(f.name);
  EXPECT_EQ(names, (std::vector<std::string>{"x", "y", "z", "intensity", "ring", "time"}));
  EXPECT_EQ(fields[4].datatype, pcl::PCLPointField::UINT16);
  EXPECT_EQ(fields[5].datatype, pcl::PCLPointField::FLOAT32);
}

TEST(PointTypes, LabeledPointCarriesLabelAndIndex) {
  std::vector<pcl::PCLPointField> fields;
  pcl::getFields<ud::LabeledPoint>(fields);
  ASSERT_EQ(fields.size(), 6u);
  EXPECT_EQ(fields[4].name, "label");
  EXPECT_EQ(fields[4].datatype, pcl::PCLPointField::UINT32);
  EXPECT_EQ(fields[5].name, "index");
  EXPECT_EQ(fields[5].datatype, pcl::PCLPointField::UINT32);
}
