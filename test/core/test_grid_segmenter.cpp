// Tests of the simple-grid segmentation (paper Sec. 3.1) on synthetic scenes.
#include "urban_detection/core/common/point_types.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "segmentation_scene.h"
#include "urban_detection/core/segmentation/grid_segmenter.h"
#include "urban_detection/core/segmentation/simple_grid.h"

namespace urban_detection {
namespace {

using core::GridSegmenter;
using core::GridSegmenterParams;
using core::SegmentClass;

constexpr float kKittiHeight = 1.73f;

PointXYZIRT pt(float x, float y, float z) {
  return makePoint(x, y, z, 1.0f);
}

int countLabel(const std::vector<SegmentClass>& labels, SegmentClass c) {
  int n = 0;
  for (SegmentClass l : labels) n += l == c;
  return n;
}

// ------------------------------------------------------------------------------------------
// SimpleGrid

TEST(SimpleGrid, CellStatisticsMatchHandComputedValues) {
  core::SimpleGridParams gp;
  gp.cell_size_m = 1.0;
  gp.max_range_m = 10.0;
  core::SimpleGrid grid(gp);
  CloudXYZIRT cloud;
  cloud.push_back(pt(0.2f, 0.3f, -1.0f));  // cell containing (0.5, 0.5)
  cloud.push_back(pt(0.7f, 0.9f, 0.5f));   // same cell
  cloud.push_back(pt(0.1f, 0.1f, -0.5f));  // same cell
  cloud.push_back(pt(-0.5f, 0.5f, 2.0f));  // neighbouring cell in -x
  grid.build(cloud, 1.0f);                 // heights become z + 1
  ASSERT_EQ(grid.rows(), 20);
  const std::int32_t c = grid.pointCell(0);
  EXPECT_EQ(grid.pointCell(1), c);
  EXPECT_EQ(grid.pointCell(2), c);
  EXPECT_EQ(grid.pointCell(3), c - 1);
  EXPECT_EQ(grid.rowOf(c), 10);
  EXPECT_EQ(grid.colOf(c), 10);
  const core::GridCell& cell = grid.cell(c);
  EXPECT_EQ(cell.count, 3u);
  EXPECT_FLOAT_EQ(cell.z_min, 0.0f);
  EXPECT_FLOAT_EQ(cell.z_max, 1.5f);
  EXPECT_FLOAT_EQ(cell.zMean(), (0.0f + 1.5f + 0.5f) / 3.0f);
  EXPECT_FLOAT_EQ(grid.pointHeight(3), 3.0f);
  float x, y;
  grid.cellCenter(c, &x, &y);
  EXPECT_FLOAT_EQ(x, 0.5f);
  EXPECT_FLOAT_EQ(y, 0.5f);
  EXPECT_EQ(grid.occupiedCells().size(), 2u);
}

TEST(SimpleGrid, SkipsNonFiniteHugeAndOutOfRangePoints) {
  core::SimpleGridParams gp;
  gp.cell_size_m = 0.5;
  gp.max_range_m = 20.0;
  core::SimpleGrid grid(gp);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  CloudXYZIRT cloud;
  cloud.push_back(pt(nan, 1.0f, 0.0f));
  cloud.push_back(pt(1.0f, inf, 0.0f));
  cloud.push_back(pt(1.0f, 1.0f, -inf));
  cloud.push_back(pt(1e30f, 1.0f, 0.0f));
  cloud.push_back(pt(1.0f, 1.0f, 1e30f));
  cloud.push_back(pt(25.0f, 0.0f, 0.0f));  // beyond max range
  cloud.push_back(pt(1.0f, 1.0f, 0.0f));   // the only valid one
  grid.build(cloud, 1.73f);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(grid.pointCell(i), core::SimpleGrid::kNoCell) << i;
  EXPECT_NE(grid.pointCell(6), core::SimpleGrid::kNoCell);
  EXPECT_EQ(grid.occupiedCells().size(), 1u);
}

TEST(SimpleGrid, RebuildResetsTheCellsOfThePreviousFrame) {
  core::SimpleGrid grid;
  CloudXYZIRT a, b;
  a.push_back(pt(3.0f, 3.0f, 5.0f));
  b.push_back(pt(3.1f, 3.1f, -1.0f));
  grid.build(a, 0.0f);
  grid.build(b, 0.0f);
  const core::GridCell& cell = grid.cell(grid.pointCell(0));
  EXPECT_EQ(cell.count, 1u);
  EXPECT_FLOAT_EQ(cell.z_max, -1.0f);
}

// ------------------------------------------------------------------------------------------
// Ground: flat, sloped, cambered, curbs

TEST(GridSegmenter, FlatGroundIsGround) {
  CloudXYZIRT cloud;
  test::sampleSurface(&cloud, kKittiHeight, -30.f, 30.f, -30.f, 30.f, 0.2f,
                      [](float, float) { return 0.0f; });
  GridSegmenter seg;
  std::vector<SegmentClass> labels;
  seg.segment(cloud, &labels);
  ASSERT_EQ(labels.size(), cloud.size());
  EXPECT_EQ(countLabel(labels, SegmentClass::kGround), static_cast<int>(cloud.size()));
}

TEST(GridSegmenter, FivePercentSlopeWithCamberStaysGround) {
  // 5 % uphill along x (3 m higher at 60 m, far beyond the ground tolerance and the seed
  // height) with a 2.5 % camber falling to both sides of the road centre line.
  CloudXYZIRT cloud;
  test::sampleSurface(&cloud, kKittiHeight, -20.f, 60.f, -15.f, 15.f, 0.2f,
                      [](float x, float y) { return 0.05f * x - 0.025f * std::fabs(y); });
  GridSegmenter seg;
  std::vector<SegmentClass> labels;
  seg.segment(cloud, &labels);
  EXPECT_EQ(countLabel(labels, SegmentClass::kGround), static_cast<int>(cloud.size()));
  // The plane below the sensor alone would not do: at x = 60 the road is 3 m up, above the
  // tall threshold, so the terrain model must follow it.
  EXPECT_GT(0.05f * 60.0f, static_cast<float>(seg.params().tall_min_height_m));
}

TEST(GridSegmenter, CurbAndSidewalkStayGround) {
  // Road for y < 5, a 0.15 m curb face at y = 5, sidewalk up to y = 9, then a second 0.12 m
  // step to a raised footpath: all of it is ground.
  CloudXYZIRT cloud;
  auto h = [](float, float y) { return y < 5.0f ? 0.0f : (y < 9.0f ? 0.15f : 0.27f); };
  test::sampleSurface(&cloud, kKittiHeight, -30.f, 30.f, -10.f, 14.f, 0.2f, h);
  for (float x = -30.f; x <= 30.f; x += 0.2f) {  // the curb face
    for (float z = 0.0f; z <= 0.15f; z += 0.05f) cloud.push_back(pt(x, 5.0f, z - kKittiHeight));
  }
  GridSegmenter seg;
  std::vector<SegmentClass> labels;
  seg.segment(cloud, &labels);
  EXPECT_EQ(countLabel(labels, SegmentClass::kGround), static_cast<int>(cloud.size()));
}

TEST(GridSegmenter, CurbInsideACellWithMostPointsOnTheRoadIsGroundWithCurbCells) {
  // The simulated drive's false objects: a 0.14 m curb at y = 5.3, inside
  // the cells 5.0..5.5 m, with three of their five rows of points on the road. A flat cell's
  // ground is its mean (0.056 m), which puts the sidewalk points 0.084 m above it, beyond the
  // 0.08 m tolerance: they form a short strip 0.2 m wide along the curb unless
  // curb_cells_ground is set.
  CloudXYZIRT cloud;
  for (int i = 0; i <= 300; ++i) {
    const float x = -15.0f + 0.1f * static_cast<float>(i);
    for (int j = 0; j <= 100; ++j) {
      const float y = 0.05f + 0.1f * static_cast<float>(j);  // rows at 5.05 .. 5.45 in the cell
      cloud.push_back(pt(x, y, (y < 5.3f ? 0.0f : 0.14f) - kKittiHeight));
    }
  }
  GridSegmenterParams p;
  GridSegmenter off(p);
  std::vector<SegmentClass> labels;
  off.segment(cloud, &labels);
  EXPECT_GT(countLabel(labels, SegmentClass::kShort), 500) << "the default keeps the strip";
  p.curb_cells_ground = true;
  GridSegmenter seg(p);
  seg.segment(cloud, &labels);
  EXPECT_EQ(countLabel(labels, SegmentClass::kShort), 0);
  EXPECT_EQ(countLabel(labels, SegmentClass::kGround), static_cast<int>(cloud.size()));
  // A low object is still an object: a 0.3 m high box on the road (a step the growing refuses).
  for (float x = 3.0f; x <= 3.4f; x += 0.1f) {
    for (float z = 0.05f; z <= 0.3f; z += 0.05f) cloud.push_back(pt(x, 2.0f, z - kKittiHeight));
  }
  seg.segment(cloud, &labels);
  EXPECT_GT(countLabel(labels, SegmentClass::kShort), 20);
}

// ------------------------------------------------------------------------------------------
// Objects

TEST(GridSegmenter, FacadeIsTallAndCarIsShort) {
  // KITTI geometry: a 3.5 m facade 14 m to the left (seen up to 1.73 + 14 tan 2 = 2.2 m,
  // above the 2.0 m tall threshold), a 4.5 x 1.8 x 1.5 m car 8 m ahead on the right.
  std::vector<test::Box> boxes = {{-25.f, 14.f, 0.f, 25.f, 14.5f, 3.5f, 1},
                                  {8.f, -5.f, 0.f, 12.5f, -3.2f, 1.5f, 2}};
  std::vector<int> tags;
  CloudXYZIRT cloud = test::rayCast(kKittiHeight, boxes, &tags);
  GridSegmenter seg;
  std::vector<SegmentClass> labels;
  seg.segment(cloud, &labels);
  // Object points within a few cm of the ground are legitimately ground (the local ground
  // estimate of a mixed cell is its lowest point): judge objects from twice the tolerance up.
  const float tol = 2.0f * static_cast<float>(seg.params().ground_tolerance_m);
  int wall = 0, wall_tall = 0, car = 0, car_short = 0, car_tall = 0, ground = 0, ground_ok = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const float h = cloud[i].z + kKittiHeight;
    // Beyond ~35 m the rings of this 64-beam pattern are more than ground_max_gap_m apart and
    // their cells hold fewer than min_points_per_cell points: clutter by design.
    if (tags[i] == 0 && std::hypot(cloud[i].x, cloud[i].y) < 35.0f) {
      ++ground;
      ground_ok += labels[i] == SegmentClass::kGround;
    } else if (tags[i] == 1 && h > tol) {
      ++wall;
      wall_tall += labels[i] == SegmentClass::kTall;
    } else if (tags[i] == 2 && h > tol) {
      ++car;
      car_short += labels[i] == SegmentClass::kShort;
      car_tall += labels[i] == SegmentClass::kTall;
    }
  }
  ASSERT_GT(wall, 500);
  ASSERT_GT(car, 300);
  EXPECT_EQ(wall_tall, wall);
  // A roof-edge return alone in its cell is clutter (sparse cell), never tall.
  EXPECT_EQ(car_tall, 0);
  EXPECT_GE(car_short, car - car / 100);
  EXPECT_EQ(ground_ok, ground);
}

// Share of the points of box `tag` (above twice the ground tolerance) labelled `cls`.
double shareOf(const CloudXYZIRT& cloud, const std::vector<int>& tags,
               const std::vector<SegmentClass>& labels, int tag, SegmentClass cls) {
  int n = 0, k = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (tags[i] != tag || cloud[i].z + kKittiHeight < 0.16f) continue;
    ++n;
    k += labels[i] == cls;
  }
  return n == 0 ? -1.0 : static_cast<double>(k) / n;
}

TEST(GridSegmenter, BusSeenWholeIsShortButWallKioskByATreeAndCutOffStructureStayTall) {
  // A sensor seeing up to 15 deg (so the objects are seen whole): a 12 x 2.5 x 3.2 m bus 15 m to
  // the left; a wall as high, 30 m long, 15 m to the right; a 4 m high 4 x 4 m kiosk 12 m behind
  // with a 5 m tree crown beside it. All but the crown are taller than tall_min_height_m and
  // lower than vehicle_max_height_m; only the bus fits a vehicle box on its own.
  std::vector<test::Box> boxes = {{-4.f, 15.f, 0.f, 8.f, 17.5f, 3.2f, 1},
                                  {-15.f, -15.5f, 0.f, 15.f, -15.f, 3.2f, 2},
                                  {-16.f, -2.f, 0.f, -12.f, 2.f, 3.8f, 3},
                                  {-16.f, 2.f, 0.f, -12.f, 6.f, 5.0f, 4}};
  std::vector<int> tags;
  CloudXYZIRT cloud = test::rayCast(kKittiHeight, boxes, &tags, 64, 1500, 15.0f);
  GridSegmenterParams p;
  p.hough.enabled = false;  // judge the cell classes alone
  p.fov_top_elevation_deg = 14.0;
  p.vehicle_max_height_m = 0.0;
  std::vector<SegmentClass> labels;
  GridSegmenter(p).segment(cloud, &labels);
  EXPECT_GT(shareOf(cloud, tags, labels, 1, SegmentClass::kTall), 0.5);  // the rule's case
  p.vehicle_max_height_m = 4.0;
  GridSegmenter on(p);
  on.segment(cloud, &labels);
  EXPECT_GT(shareOf(cloud, tags, labels, 1, SegmentClass::kShort), 0.95);
  EXPECT_GT(shareOf(cloud, tags, labels, 2, SegmentClass::kTall), 0.9);
  EXPECT_GT(shareOf(cloud, tags, labels, 3, SegmentClass::kTall), 0.9);  // joined to the crown
  // Where the bus reaches the upper edge of the field of view its height is unknown (it could
  // be a facade seen up to that edge): it stays tall.
  p.fov_top_elevation_deg = 1.0;
  on.setParams(p);
  on.segment(cloud, &labels);
  EXPECT_GT(shareOf(cloud, tags, labels, 1, SegmentClass::kTall), 0.5);
}

TEST(GridSegmenter, MixedCellIsSplitPerPointByHeightAboveLocalGround) {
  // One 0.5 m cell holding road points and the lower edge of a car body 0.4-1.2 m up.
  CloudXYZIRT cloud;
  test::sampleSurface(&cloud, kKittiHeight, -10.f, 10.f, -10.f, 10.f, 0.1f,
                      [](float, float) { return 0.0f; });
  const std::size_t n_ground = cloud.size();
  for (float z = 0.4f; z <= 1.2f; z += 0.1f) {
    for (float y = 4.05f; y < 6.0f; y += 0.1f) cloud.push_back(pt(6.05f, y, z - kKittiHeight));
  }
  GridSegmenter seg;
  std::vector<SegmentClass> labels;
  seg.segment(cloud, &labels);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(labels[i], i < n_ground ? SegmentClass::kGround : SegmentClass::kShort) << i;
  }
}

TEST(GridSegmenter, SparseCellsAreClutter) {
  CloudXYZIRT cloud;
  test::sampleSurface(&cloud, kKittiHeight, -10.f, 10.f, -10.f, 10.f, 0.1f,
                      [](float, float) { return 0.0f; });
  const std::size_t first = cloud.size();
  // Two points floating 1 m up just beyond the road's edge (a bird, a wire) and two isolated
  // points 40 m away where there is no terrain at all.
  cloud.push_back(pt(11.1f, 11.1f, 1.0f - kKittiHeight));
  cloud.push_back(pt(11.2f, 11.2f, 1.1f - kKittiHeight));
  cloud.push_back(pt(40.1f, -30.1f, 0.0f - kKittiHeight));
  cloud.push_back(pt(40.2f, -30.2f, 0.3f - kKittiHeight));
  GridSegmenter seg;
  std::vector<SegmentClass> labels;
  seg.segment(cloud, &labels);
  ASSERT_GE(seg.params().min_points_per_cell, 3);
  for (std::size_t i = first; i < cloud.size(); ++i) EXPECT_EQ(labels[i], SegmentClass::kClutter);
}

TEST(GridSegmenter, SparseFarRoadIsGroundOnlyWhenEnabled) {
  CloudXYZIRT cloud;
  test::sampleSurface(&cloud, kKittiHeight, -10.f, 20.f, -10.f, 10.f, 0.1f,
                      [](float, float) { return 0.0f; });
  const std::size_t first = cloud.size();
  cloud.push_back(pt(21.1f, 0.1f, 0.02f - kKittiHeight));  // 1-point cells next to the road
  cloud.push_back(pt(21.7f, 0.1f, 0.0f - kKittiHeight));
  GridSegmenterParams p;
  GridSegmenter seg(p);
  std::vector<SegmentClass> labels;
  seg.segment(cloud, &labels);
  EXPECT_EQ(labels[first], SegmentClass::kGround);
  EXPECT_EQ(labels[first + 1], SegmentClass::kGround);
  p.ground_in_sparse_cells = false;
  seg.setParams(p);
  seg.segment(cloud, &labels);
  EXPECT_EQ(labels[first], SegmentClass::kClutter);
  EXPECT_EQ(labels[first + 1], SegmentClass::kClutter);
}

// ------------------------------------------------------------------------------------------
// Hough wall refinement (paper Fig. 3)

// The paper's situation: a sensor mounted lower (1.2 m) and the paper's 1.40 m tall threshold.
// A facade 4 m to the side is seen only up to 1.2 + d tan(2 deg), i.e. below 1.4 m for
// d < 5.7 m: without refinement those cells are short objects.
struct FacadeScene {
  FacadeScene() {
    boxes = {{-25.f, 4.f, 0.f, 25.f, 4.4f, 8.f, 1},     // facade along x
             {6.f, -6.f, 0.f, 10.5f, -4.2f, 1.1f, 2}};  // an isolated low car
    cloud = test::rayCast(1.2f, boxes, &tags);
    params.sensor_height_m = 1.2;
    params.tall_min_height_m = 1.4;
  }
  std::vector<test::Box> boxes;
  std::vector<int> tags;
  CloudXYZIRT cloud;
  GridSegmenterParams params;
};

TEST(HoughWallRefiner, FacadeSeenOnlyBelowTallThresholdNearTheSensorBecomesTall) {
  FacadeScene s;
  std::vector<SegmentClass> labels;
  auto count = [&](int tag, SegmentClass c, float min_h) {
    int n = 0;
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
      n += s.tags[i] == tag && s.cloud[i].z + 1.2f > min_h && labels[i] == c;
    }
    return n;
  };
  const float above = 2.0f * static_cast<float>(s.params.ground_tolerance_m);
  s.params.hough.enabled = false;
  GridSegmenter without(s.params);
  without.segment(s.cloud, &labels);
  const int short_without = count(1, SegmentClass::kShort, above);
  EXPECT_GT(short_without, 100) << "the scene must reproduce the misreading";

  s.params.hough.enabled = true;
  GridSegmenter with(s.params);
  with.segment(s.cloud, &labels);
  EXPECT_EQ(count(1, SegmentClass::kShort, above), 0);
  EXPECT_GT(with.stats().hough.cells_relabeled, 0);
  // The car is left alone.
  int car = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i)
    car += s.tags[i] == 2 && s.cloud[i].z + 1.2f > above;
  EXPECT_GT(car, 100);
  EXPECT_EQ(count(2, SegmentClass::kTall, above), 0);
  EXPECT_GE(count(2, SegmentClass::kShort, above), car - car / 100);
}

TEST(HoughWallRefiner, RowOfParkedCarsIsNotAWall) {
  // Five cars bumper to bumper (0.8 m gaps) along the kerb: a long straight line of short
  // cells, but none is tall or reaches the top of the field of view.
  std::vector<test::Box> boxes;
  for (int k = 0; k < 5; ++k) {
    const float x0 = -12.f + k * 5.3f;
    boxes.push_back({x0, 5.f, 0.f, x0 + 4.5f, 6.8f, 1.5f, 2});
  }
  std::vector<int> tags;
  CloudXYZIRT cloud = test::rayCast(kKittiHeight, boxes, &tags);
  GridSegmenter seg;
  std::vector<SegmentClass> labels;
  seg.segment(cloud, &labels);
  int car = 0, car_short = 0, car_tall = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (tags[i] != 2 || cloud[i].z + kKittiHeight <= 2.0 * seg.params().ground_tolerance_m) {
      continue;
    }
    ++car;
    car_short += labels[i] == SegmentClass::kShort;
    car_tall += labels[i] == SegmentClass::kTall;
  }
  ASSERT_GT(car, 1000);
  EXPECT_EQ(car_tall, 0);
  EXPECT_GE(car_short, car - car / 100);  // single roof-edge returns are clutter
}

// ASCII-art cell grid: 'T' tall, 's' short, '.' ground, '!' short with wall support.
struct AsciiGrid {
  explicit AsciiGrid(const std::vector<std::string>& rows_top_down) {
    rows = static_cast<int>(rows_top_down.size());
    cols = static_cast<int>(rows_top_down[0].size());
    classes.assign(static_cast<std::size_t>(rows) * cols, SegmentClass::kGround);
    support.assign(classes.size(), 0);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        const char ch = rows_top_down[rows - 1 - r][c];
        const std::size_t i = static_cast<std::size_t>(r) * cols + c;
        if (ch == 'T') classes[i] = SegmentClass::kTall;
        if (ch == 's' || ch == '!') classes[i] = SegmentClass::kShort;
        if (ch == '!') support[i] = 1;
      }
    }
  }
  std::string row(int r_top_down) const {
    std::string s;
    const int r = rows - 1 - r_top_down;
    for (int c = 0; c < cols; ++c) {
      const SegmentClass k = classes[static_cast<std::size_t>(r) * cols + c];
      s += k == SegmentClass::kTall ? 'T' : (k == SegmentClass::kShort ? 's' : '.');
    }
    return s;
  }
  int rows = 0, cols = 0;
  std::vector<SegmentClass> classes;
  std::vector<std::uint8_t> support;
};

// Refiner parameters for the 1 m cells of the ASCII grids: 6 m walls, 1 m gaps, 80 % support.
core::HoughWallRefinerParams asciiRefinerParams() {
  core::HoughWallRefinerParams p;
  p.max_range_m = 100.0;
  p.votes = 6;
  p.min_line_length_m = 6.0;
  p.max_line_gap_m = 1.0;
  p.line_half_width_cells = 0;
  p.min_tall_fraction = 0.8;
  return p;
}

TEST(HoughWallRefiner, AsciiWallRunIsRelabelledAndCarsAreNot) {
  // 1 m cells. Row 1: a wall, tall at both ends, its middle seen short but reaching the top
  // of the field of view ('!'). Row 4: a wall run broken by a 4 m gap from a car ('sss'):
  // the car is not part of the run. Row 7: cars in a row, never a wall.
  AsciiGrid g({"................................", "TTTTT!!!!!!!!!!!!!!TTTTTTT......",
               "................................", "................................",
               "TTTTTTTTTTTTTT....sss...........", "................................",
               "................................", "ssss.ssss.ssss.ssss.ssss........",
               "................................"});
  core::HoughWallRefinerParams p = asciiRefinerParams();
  core::HoughWallRefiner refiner(p);
  const std::vector<SegmentClass> before = g.classes;
  const core::HoughWallStats st = refiner.refine(g.rows, g.cols, 1.0, &g.classes, &g.support);
  EXPECT_EQ(g.row(1), "TTTTTTTTTTTTTTTTTTTTTTTTTT......");
  EXPECT_EQ(g.row(4), "TTTTTTTTTTTTTT....sss...........");
  EXPECT_EQ(g.row(7), "ssss.ssss.ssss.ssss.ssss........");
  EXPECT_EQ(st.cells_relabeled, 14);
  // relabeledCells() lists exactly the cells that changed (the segmenter patches its per-point
  // table with it): the 14 '!' cells of row 1, each once.
  std::vector<std::int32_t> changed;
  for (std::size_t i = 0; i < before.size(); ++i) {
    if (before[i] != g.classes[i]) changed.push_back(static_cast<std::int32_t>(i));
  }
  std::vector<std::int32_t> listed = refiner.relabeledCells();
  std::sort(listed.begin(), listed.end());
  EXPECT_EQ(listed, changed);
  EXPECT_EQ(changed.size(), 14u);
  // Without the wall-support evidence the middle of row 1 is 14 short of 21 cells: rejected.
  AsciiGrid h({"................................", "TTTTT!!!!!!!!!!!!!!TTTTTTT......",
               "................................"});
  refiner.refine(h.rows, h.cols, 1.0, &h.classes);
  EXPECT_EQ(h.row(1), "TTTTTssssssssssssssTTTTTTT......");
  EXPECT_TRUE(refiner.relabeledCells().empty());
}

TEST(HoughWallRefiner, FacadeContinuingARowOfCarsIsAWallAndAVanAmongCarsIsNot) {
  // 1 m cells. Row 1: parked cars, one empty cell, then a facade seen short but reaching the
  // top of the field of view ('!') ending in tall cells: one run of 25 occupied cells, 16 of
  // them supporting (0.64 < 0.8), yet the 16 m supported stretch is a facade (the simulated
  // drive's narrow street). Row 4: a van ('!!!!!', 5 m, truncated by the field of view)
  // between cars: its supported stretch is shorter than a vehicle-proof wall.
  AsciiGrid g({"................................", "sssssssss.!!!!!!!!!!!!TTTT......",
               "................................", "................................",
               "ssss.ssss.!!!!!.ssss.ssss.......", "................................"});
  core::HoughWallRefinerParams p = asciiRefinerParams();
  p.min_mixed_wall_length_m = 8.0;
  core::HoughWallRefiner refiner(p);
  refiner.refine(g.rows, g.cols, 1.0, &g.classes, &g.support);
  EXPECT_EQ(g.row(1), "sssssssss.TTTTTTTTTTTTTTTT......");
  EXPECT_EQ(g.row(4), "ssss.ssss.sssss.ssss.ssss.......");
  EXPECT_EQ(refiner.relabeledCells().size(), 12u);

  // A bin ('ss', short, not truncated by the field of view) against that facade, with a line
  // half width of one cell: the facade's own cells change, the bin and the cars do not.
  AsciiGrid b({"................................", "..............ss................",
               "sssssssss.!!!!!!!!!!!!TTTT......", "................................"});
  p.line_half_width_cells = 1;
  refiner.setParams(p);
  refiner.refine(b.rows, b.cols, 1.0, &b.classes, &b.support);
  EXPECT_EQ(b.row(1), "..............ss................");
  EXPECT_EQ(b.row(2), "sssssssss.TTTTTTTTTTTTTTTT......");
  p.line_half_width_cells = 0;

  // With the mixed-run rule off, the cars veto the facade (the behaviour before it).
  AsciiGrid h({"................................", "sssssssss.!!!!!!!!!!!!TTTT......",
               "................................"});
  p.min_mixed_wall_length_m = 0.0;
  refiner.setParams(p);
  refiner.refine(h.rows, h.cols, 1.0, &h.classes, &h.support);
  EXPECT_EQ(h.row(1), "sssssssss.ssssssssssssTTTT......");
}

TEST(HoughWallRefiner, RejectsInconsistentInput) {
  core::HoughWallRefiner refiner;
  std::vector<SegmentClass> cls(10, SegmentClass::kShort);
  EXPECT_EQ(refiner.refine(4, 4, 0.5, &cls).cells_relabeled, 0);  // size mismatch
  EXPECT_EQ(refiner.refine(0, 0, 0.5, &cls).lines_found, 0);
}

// ------------------------------------------------------------------------------------------
// Degenerate input, outputs, frame-to-frame state

TEST(GridSegmenter, EmptyAndAllNaNClouds) {
  GridSegmenter seg;
  std::vector<SegmentClass> labels(7, SegmentClass::kTall);
  CloudXYZIRT empty;
  seg.segment(empty, &labels);
  EXPECT_TRUE(labels.empty());
  CloudXYZIRT bad;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (int i = 0; i < 100; ++i) bad.push_back(pt(nan, nan, nan));
  bad.push_back(pt(inf, 0.f, 0.f));
  bad.push_back(pt(1e30f, 1e30f, 1e30f));
  bad.push_back(pt(-1e30f, 3.f, -1.7f));
  seg.segment(bad, &labels);
  ASSERT_EQ(labels.size(), bad.size());
  EXPECT_EQ(countLabel(labels, SegmentClass::kUnknown), static_cast<int>(bad.size()));
  EXPECT_EQ(seg.stats().points_unknown, bad.size());
  EXPECT_EQ(seg.stats().points_non_finite, 101u);  // the 1e30 points are finite, out of range
  LabeledCloud fg;
  core::extractForeground(bad, labels, &fg);
  EXPECT_TRUE(fg.empty());
}

// The foreground extraction (16 labels compared at a time) against the plain loop over the
// labels: random labels in runs and alone, short points that are not finite, cloud sizes
// around multiples of 16.
TEST(GridSegmenter, ForegroundEqualsThePlainLoop) {
  std::mt19937 rng(5);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int trial = 0; trial < 60; ++trial) {
    const std::size_t n = trial < 40 ? static_cast<std::size_t>(trial) : 1000 + rng() % 3000;
    CloudXYZIRT cloud;
    std::vector<SegmentClass> labels;
    for (std::size_t i = 0; i < n; ++i) {
      const float v = static_cast<float>(i);
      cloud.push_back(rng() % 23 == 0 ? pt(nan, v, 0.f) : pt(v, -v, 0.5f * v));
      cloud.back().intensity = static_cast<float>(rng() % 256);
      const bool in_run = !labels.empty() && labels.back() == SegmentClass::kShort && rng() % 4;
      labels.push_back(in_run || rng() % 9 == 0 ? SegmentClass::kShort
                                                : static_cast<SegmentClass>(rng() % 4));
    }
    LabeledCloud fg;
    core::extractForeground(cloud, labels, &fg);
    std::vector<std::uint32_t> expected;  // the plain loop
    for (std::size_t i = 0; i < n; ++i) {
      if (labels[i] == SegmentClass::kShort && std::isfinite(cloud[i].x)) expected.push_back(i);
    }
    ASSERT_EQ(fg.size(), expected.size()) << "trial " << trial;
    ASSERT_EQ(fg.width, expected.size());
    for (std::size_t k = 0; k < expected.size(); ++k) {
      const LabeledPoint& q = fg[k];
      const PointXYZIRT& p = cloud[expected[k]];
      ASSERT_EQ(q.index, expected[k]) << "trial " << trial;
      EXPECT_EQ(q.x, p.x);
      EXPECT_EQ(q.y, p.y);
      EXPECT_EQ(q.z, p.z);
      EXPECT_EQ(q.intensity, p.intensity);
      EXPECT_EQ(q.label, static_cast<std::uint32_t>(SegmentClass::kShort));
    }
  }
}

TEST(GridSegmenter, ForegroundAndLabelledCloudCarryIndices) {
  std::vector<test::Box> boxes = {{8.f, -5.f, 0.f, 12.5f, -3.2f, 1.5f, 2}};
  std::vector<int> tags;
  CloudXYZIRT cloud = test::rayCast(kKittiHeight, boxes, &tags);
  cloud.push_back(pt(std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f));
  tags.push_back(-1);
  cloud.header.frame_id = "velodyne";
  cloud.header.stamp = 123456;
  GridSegmenter seg;
  std::vector<SegmentClass> labels;
  seg.segment(cloud, &labels);
  LabeledCloud fg, all;
  core::extractForeground(cloud, labels, &fg);
  core::buildLabeledCloud(cloud, labels, &all);
  ASSERT_EQ(all.size(), cloud.size());
  EXPECT_FALSE(all.is_dense);
  EXPECT_EQ(all.back().label, static_cast<std::uint32_t>(SegmentClass::kUnknown));
  EXPECT_EQ(fg.header.frame_id, "velodyne");
  EXPECT_EQ(fg.header.stamp, 123456u);
  ASSERT_EQ(fg.size(), static_cast<std::size_t>(countLabel(labels, SegmentClass::kShort)));
  ASSERT_GT(fg.size(), 100u);
  for (const LabeledPoint& q : fg) {
    ASSERT_LT(q.index, cloud.size());
    EXPECT_EQ(tags[q.index], 2);  // only car points are foreground here
    EXPECT_EQ(q.x, cloud[q.index].x);
    EXPECT_EQ(q.z, cloud[q.index].z);
    EXPECT_EQ(q.label, static_cast<std::uint32_t>(SegmentClass::kShort));
  }
  for (std::size_t i = 0; i + 1 < all.size(); ++i) {
    EXPECT_EQ(all[i].index, i);
    EXPECT_EQ(all[i].label, static_cast<std::uint32_t>(labels[i]));
  }
}

TEST(GridSegmenter, ReusedSegmenterMatchesAFreshOne) {
  // Scratch buffers are reset between frames: frame B after frame A gives exactly what a
  // fresh segmenter gives on B.
  std::vector<int> tags;
  CloudXYZIRT a = test::rayCast(
      kKittiHeight, {{-25.f, 6.f, 0.f, 25.f, 6.5f, 6.f, 1}, {5.f, -4.f, 0.f, 9.5f, -2.2f, 1.5f, 2}},
      &tags);
  CloudXYZIRT b = test::rayCast(
      kKittiHeight,
      {{10.f, -20.f, 0.f, 10.5f, 20.f, 4.f, 1}, {-9.f, 2.f, 0.f, -4.5f, 3.8f, 1.6f, 2}}, &tags);
  GridSegmenter reused, fresh;
  std::vector<SegmentClass> la, lb, lf;
  reused.segment(a, &la);
  reused.segment(b, &lb);
  fresh.segment(b, &lf);
  EXPECT_EQ(lb, lf);
}

TEST(GridSegmenter, RingAndTimeAreNotNeeded) {
  std::vector<int> tags;
  CloudXYZIRT cloud = test::rayCast(kKittiHeight, {{8.f, -5.f, 0.f, 12.5f, -3.2f, 1.5f, 2}}, &tags);
  CloudXYZIRT zeroed = cloud;
  for (auto& p : zeroed) p.ring = 0, p.time = 0.f;
  GridSegmenter s1, s2;
  std::vector<SegmentClass> l1, l2;
  s1.segment(cloud, &l1);
  s2.segment(zeroed, &l2);
  EXPECT_EQ(l1, l2);
}

}  // namespace
}  // namespace urban_detection
