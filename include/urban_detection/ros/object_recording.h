/// \file object_recording.h
/// What the ObjectRecorder writes per revolution, so a live or bag run can be scored and read
/// by other tools: per-point instance labels (the format `urban_detection_eval --detections`
/// scores), KITTI-format label lines and one CSV line per object. No ROS master needed.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "urban_detection/DetectedObjectArray.h"

namespace urban_detection {
namespace ros_conv {

/// One uint32 per point of the segmented input cloud (`cloud_size` points): the 1-based
/// position of the object holding it in `objects` (0 = none). False when an index is out of
/// range (the objects do not belong to a cloud of that size).
bool instanceLabels(const DetectedObjectArray& objects, std::size_t cloud_size,
                    std::vector<std::uint32_t>* labels);

/// A KITTI object label line of `object` (type truncated occluded alpha x1 y1 x2 y2 h w l x y z
/// rotation_y score): type from the class (vehicle -> Car, pedestrian -> Pedestrian, cyclist ->
/// Cyclist, other -> Misc, unknown -> DontCare), the yaw-oriented box in the nominal KITTI
/// camera axes (x_cam = -y, y_cam = -z, z_cam = x of the LiDAR frame; location = centre of the
/// box's bottom face, rotation_y = -yaw - pi/2), no image box (0 0 0 0), truncated 0,
/// occluded 0, alpha -10, score = class confidence.
std::string kittiLabelLine(const DetectedObject& object);

/// The CSV header of csvLine.
std::string csvHeader();

/// revolution,stamp_s,frame_id,id,class,confidence,points,x,y,z,length,width,height,yaw_rad
/// (box centre and size [m], yaw [rad] in the objects' frame).
std::string csvLine(std::uint64_t revolution, const std_msgs::Header& header,
                    const DetectedObject& object);

}  // namespace ros_conv
}  // namespace urban_detection
