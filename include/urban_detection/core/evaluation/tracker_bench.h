/// \file tracker_bench.h
//// The tracker's timing case of urban_detection_bench: a synthetic street of `objects` objects
/// (parked cars on both sides, cars driving both ways, pedestrians), seen from a sensor driving
/// at 8 m/s, for `revolutions` revolutions at 10 Hz. Each object is the points of its faces that
/// face the sensor (three scan rows, a point every 0.1 m, 3 cm of noise); 5 % of the detections
/// are missed. The box fitting of the objects (BoxFitter, default parameters) and the tracker
/// update are timed through `time(stage, call)` as "box_fitting_100_objects" and
/// "tracker_100_objects". ROS-free.
#pragma once

#include <functional>

namespace urban_detection {
namespace core {

/// Runs the case, calling `time(stage, call)` around each timed call.
void benchTracker(int objects, int revolutions,
                  const std::function<void(const char*, const std::function<void()>&)>& time);

}  // namespace core
}  // namespace urban_detection
