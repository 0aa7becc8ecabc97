/// \file group_splitter.h
/// Splits an object that is a group of people standing or walking side by side into one object
/// per person (ours, step 7 of the hierarchical grid, after the far-object merger). ROS-free.
///
/// People a hand's width apart (0.6-0.8 m centre to centre) leave no empty sub-cell between
/// their shoulders, so the components of the hierarchical grid hold the whole group. What
/// still separates them is the height profile: each person is a column whose top (the head) is
/// a local maximum, and between two heads the profile dips to the shoulders or to the empty
/// gap between the bodies.
///
/// Rule, for each object whose oriented box is at least `min_length_m` and at most
/// `max_length_m` long and whose z extent lies between `min_person_height_m` and
/// `max_height_m` (a group of people, or people beside a short structure or a car):
///   - the highest point per cell of a `cell_m` xy grid over the object (the height map);
///   - heads: cells at least `min_person_height_m` above the object's lowest point and higher
///     than every other cell within `min_head_spacing_m` (ties: the first in row-major order);
///   - two heads belong to the same top (a person, or one object) unless the height map between
///   them,
///     sampled every half cell along the straight line and taking at each sample the highest of
///     the cell there and its two neighbours across the line (arms on both sides of a cyclist's
///     body, a car's roof), dips at least `min_saddle_drop_m` below the lower head somewhere
///     (empty samples are skipped: scan rings leave holes; with no sample at all the heads are
///     apart); heads of one top are joined transitively;
///   - with two or more tops, each point goes to the nearest head's top (xy); a
///     top with fewer than `min_piece_points` points is dropped and its points go to the
///     others (repeated until every top has enough points or one is left);
///   - the pieces at most `max_piece_length_m` long (one person) become objects of their own;
///     the others (a car's or a structure's tops) stay together as one object. Without a
///     person-sized piece (a car's halves), or when nothing would be split off, the object
///     stays whole. A person beside a bench, a bike stand or a car is split off that way.
/// The pieces replace the object in place, in the order of their first point, each with its
/// points in the object's order and its geometry recomputed; ids are renumbered 1..N.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/core/common/param_fields.h"
#include "urban_detection/core/common/point_types.h"
#include "urban_detection/core/detection/object_detector.h"
#include "urban_detection/core/detection/object_geometry.h"

namespace urban_detection {
namespace core {

/// Parameters of GroupSplitter, mirrored in config/hierarchical_grid.yaml
/// (`hierarchical_grid: group_split:`). Physical sizes of people, not fitted to data.
struct GroupSplitterParams {
  double min_length_m = 0.0;         // [m] 0 = off (shipped off, docs/design.md); objects at
                                     //     least this long are candidates (1.0: one person,
                                     //     arms and stride included, is shorter)
  double max_length_m = 8.0;         // [m] ... and at most this long (people beside a bench,
                                     //     a bus shelter or a car)
  double max_height_m = 2.3;         // [m] ... and at most this high (z extent)
  double min_person_height_m = 1.4;  // [m] a head is at least this above the object's bottom
                                     //     (an adult's; a car's roof is at most ~1.3 m above
                                     //     its bumper, its lowest foreground point)
  double cell_m = 0.1;               // [m] side of a cell of the height map (finer than the
                                     //     0.14 m between the shoulders of people 0.6 m apart)
  double min_head_spacing_m = 0.3;   // [m] a head is the highest cell within this distance
                                     //     (the heads of people 0.6 m apart: >= 0.4 m)
  double min_saddle_drop_m = 0.2;    // [m] two people: the profile between their heads dips at
                                     //     least this below the lower head (head to shoulders)
  int min_piece_points = 10;         // [points] every piece has at least this many points
  double max_piece_length_m = 1.2;   // [m] a top's piece at most this long is a person: it
                                     //     becomes an object of its own
};

/// GroupSplitterParams' field table (core/common/param_fields.h).
template <>
struct ParamFields<GroupSplitterParams> {
  template <class P, class F>
  static void visit(P& p, F&& f) {
    f({"min_length_m", "m", 0.0, 100.0, "objects at least this long are split candidates; 0 = off"},
      p.min_length_m);
    f({"max_length_m", "m", 0.0, 100.0, "... and at most this long"}, p.max_length_m);
    f({"max_height_m", "m", 0.0, 100.0, "... and at most this high"}, p.max_height_m);
    f({"min_person_height_m", "m", 0.0, 10.0, "a head is at least this above the object's bottom"},
      p.min_person_height_m);
    f({"cell_m", "m", 0.02, 2.0, "side of a cell of the height map"}, p.cell_m);
    f({"min_head_spacing_m", "m", 0.0, 5.0, "a head is the highest cell within this distance"},
      p.min_head_spacing_m);
    f({"min_saddle_drop_m", "m", 0.0, 5.0,
       "the profile between two people's heads dips at least this below the lower one"},
      p.min_saddle_drop_m);
    f({"min_piece_points", "points", 1, 1000000, "every piece has at least this many points"},
      p.min_piece_points);
    f({"max_piece_length_m", "m", 0.0, 100.0, "a piece at most this long is split off as a person"},
      p.max_piece_length_m);
  }
};

/// "" when `p` is usable, else a message naming the first bad field and its range.
std::string validate(const GroupSplitterParams& p);

/// Splits groups of people into one object per person (see the file comment).
class GroupSplitter {
 public:
  /// Throws std::invalid_argument when validate(params) is not empty.
  explicit GroupSplitter(const GroupSplitterParams& params = GroupSplitterParams());
  const GroupSplitterParams& params() const { return params_; }

  /// `foreground` is the detector's input (points carry `index`; the objects' indices refer to
  /// it), `objects` its output with their geometry. Returns the number of objects added.
  std::size_t apply(const LabeledCloud& foreground, std::vector<DetectedObject>* objects);

 private:
  // Splits objects[k] into out_ pieces; false when it stays whole.
  bool split(const LabeledCloud& foreground, const DetectedObject& object);
  std::int32_t find(std::int32_t a);

  GroupSplitterParams params_;
  ObjectGeometry geometry_;
  // Scratch kept between calls.
  std::vector<std::uint32_t> positions_;  // the object's points in the foreground
  std::vector<float> zmax_;               // [m] height map, -inf where empty
  std::vector<std::int32_t> heads_;       // head cells
  std::vector<std::int32_t> parent_;      // union-find over heads
  std::vector<std::int32_t> person_;      // per head: person index, -1 dropped
  std::vector<std::int32_t> owner_;       // per point: person index
  std::vector<std::uint32_t> counts_;     // per person: points
  std::vector<std::vector<std::uint32_t>> piece_positions_;
  std::vector<DetectedObject> pieces_;
  std::vector<DetectedObject> first_pieces_;
  std::vector<std::uint8_t> person_sized_;  // per piece: at most max_piece_length_m long
  std::vector<std::vector<std::uint32_t>> out_positions_;
  std::vector<DetectedObject> out_;
};

}  // namespace core
}  // namespace urban_detection
