// urban_detection_params: every stage's parameters (name, default, range, unit, description),
// printed as Markdown from the field tables (core/common/param_fields.h). docs/parameters.md is
// its output, and test_tools checks that it is current:
//
//   urban_detection_params > docs/parameters.md
#include <cstdio>
#include <iostream>
#include <string>

#include "urban_detection/core/params/params_yaml.h"
#include "urban_detection/core/pipeline/early_objects.h"
#include "urban_detection/core/simulation/simulation_config.h"
#include "urban_detection/core/spark/camera_model.h"
#include "urban_detection/core/spark/spark_capture.h"
#include "urban_detection/ros/nodelet_params.h"
#include "urban_detection/ros/object_markers.h"
#include "urban_detection/ros/object_tracking.h"
#include "urban_detection/ros/packet_params.h"

using namespace urban_detection;

namespace {

template <class Params>
void section(const std::string& title, const std::string& where) {
  std::cout << "## " << title << "\n\n"
            << where << "\n\n"
            << core::fieldTableMarkdown(Params()) << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1) {
    std::fprintf(stderr,
                 "usage: urban_detection_params\n"
                 "  prints every stage's parameter table as Markdown (docs/parameters.md)\n");
    return std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help" ? 0 : 2;
  }
  std::cout
      << "# Parameters\n\n"
      << "Printed by `urban_detection_params` from the field tables beside each parameter struct\n"
         "(`include/urban_detection/core/common/param_fields.h`); do not edit by hand. The same\n"
         "names, ranges and types are used by the YAML files (offline tools), the ROS parameter\n"
         "server (nodelets, at start-up) and dynamic_reconfigure (live; the `.cfg` name of\n"
         "`hough/votes` is `hough_votes`). A value of the wrong type, an unknown YAML key or a\n"
         "number outside its range is refused with a message naming it; ranges are inclusive.\n\n";
  section<ros_conv::PacketSourceParams>(
      "Packet source (PacketSource)",
      "`config/packet_source.yaml` (top level); nodelet parameters `~<name>`.");
  section<ros_conv::PacketToCloudParams>(
      "Packet decoder (PacketToCloud)",
      "`config/packet_to_cloud.yaml` (top level); nodelet parameters `~<name>`.");
  section<core::GridSegmenterParams>(
      "Segmentation (GridSegmentation)",
      "`config/segmentation.yaml` (top level); nodelet parameters `~<name>`; tunable.");
  section<core::HierarchicalGridDetectorParams>(
      "Hierarchical grid detector (HierarchicalGridDetector)",
      "`config/hierarchical_grid.yaml`, map `hierarchical_grid:`; nodelet parameters "
      "`~hierarchical_grid/<name>`; tunable.");
  section<core::KdTreeDetectorParams>(
      "kd-tree detector (KdTreeDetector)",
      "`config/kdtree.yaml`, map `kdtree:`; nodelet parameters `~kdtree/<name>`; tunable.");
  section<core::ObjectClassifierParams>(
      "Object classifier (after either detector)",
      "`config/classification.yaml`, map `classifier:`; nodelet parameters `~classifier/<name>`; "
      "`min_object_probability` and `reject_non_objects` tunable.");
  section<core::BoxFittingParams>(
      "Box fitting (after the classifier)",
      "`config/classification.yaml`, map `box_fitting:`; nodelet parameters "
      "`~box_fitting/<name>`.");
  section<ros_conv::ObjectMarkerParams>(
      "Markers (ObjectMarkers)",
      "`config/markers.yaml`, map `markers:`; nodelet parameters `~markers/<name>`; tunable.");
  section<core::CameraStageParams>(
      "Camera stage (ImageLabelTransfer, urban_detection_spark)",
      "`config/image_label_transfer.yaml` (top level; presets such as "
      "`config/spark_enet_cityscapes.yaml` load over it); nodelet parameters `~<name>`; "
      "`urban_detection_spark --model-config`. Relative model files are found in `model/dir` "
      "(`docs/spark.md`).");
  section<core::CapturePathParams>(
      "SPARK capture path (urban_detection_spark run)",
      "the `--path PATH.json` file: these keys besides `path` (the camera positions, a list of "
      "`[x, y, z]`); `colour` is rgb, intensity or height.");
  section<core::EarlyObjectsParams>(
      "Early objects (HierarchicalGridDetector with `early_objects:=true`)",
      "nodelet parameters `~early/<name>` (defaults when absent); `docs/design.md`, "
      "\"Early objects\".");
  section<core::TrackerParams>(
      "Tracker (ObjectTracker)",
      "`config/object_tracker.yaml`, map `tracker:`; nodelet parameters `~tracker/<name>`; "
      "tunable (the fields `cfg/ObjectTracker.cfg` lists).");
  section<ros_conv::TrackMarkerParams>(
      "Track markers (ObjectTracker)",
      "`config/object_tracker.yaml`, map `markers:`; nodelet parameters `~markers/<name>`.");
  section<ros_conv::CloudInputParams>("Cloud input (CloudInput)", "nodelet parameters `~<name>`.");
  section<ros_conv::GridSegmentationNodeletParams>(
      "Segmentation nodelet (GridSegmentation)",
      "nodelet parameters `~<name>`, besides the segmentation's above.");
  section<ros_conv::DetectorNodeletParams>(
      "Detector nodelets (HierarchicalGridDetector, KdTreeDetector)",
      "nodelet parameters `~<name>`, besides the detector's, classifier's and box fitting's.");
  section<ros_conv::ObjectTrackerNodeletParams>(
      "Tracker nodelet (ObjectTracker)", "nodelet parameters `~<name>`, besides `~tracker/`.");
  section<ros_conv::ObjectQueueParams>("Object markers and export (ObjectMarkers, ObjectExport)",
                                       "nodelet parameters `~<name>`.");
  section<ros_conv::ObjectRecorderParams>("Object recorder (ObjectRecorder)",
                                          "nodelet parameters `~<name>`.");
  section<ros_conv::SimulatedSensorParams>(
      "Simulated sensor (SimulatedSensor)",
      "nodelet parameters `~<name>`; `config` names the drive file below.");
  section<core::SimulationConfig>(
      "Simulated drive (SimulatedSensor, urban_detection_simulate)",
      "`config/demo_drive.yaml` (the file's nested maps: `scene/buildings/depth_m` is "
      "`scene: {buildings: {depth_m: ...}}`; `scene/sections` is a list of maps, one per "
      "section, each with the `scene/sections[]/` keys); `urban_detection_simulate --config`.");
  return 0;
}
