/// \file tunable_detector_nodelet.h
/// A DetectorNodelet whose detector parameters are loaded from, and tunable through
/// dynamic_reconfigure in, one private sub-namespace. A detector nodelet is then a traits
/// struct:
///   struct Traits {
///     using Params = ...; using Config = ...; using Detector = ...;
///     static constexpr const char* kNamespace = "...";  // ~<kNamespace>/*
///   };
/// Params are loaded with loadFields() and every reconfigure update is validated as a whole
/// with checkFields() (the field table's ranges and validate()'s cross-field rules), then a new
/// detector replaces the old between two revolutions.
#pragma once

#include <memory>
#include <string>

#include <ros/node_handle.h>

#include "urban_detection/ros/detector_nodelet.h"
#include "urban_detection/ros/param_loading.h"
#include "urban_detection/ros/tunable_fields.h"
#include "urban_detection/ros/validated_reconfigure.h"

namespace urban_detection {
namespace ros_conv {

template <class Traits>
class TunableDetectorNodelet : public DetectorNodelet {
  using Params = typename Traits::Params;
  using Config = typename Traits::Config;
  using Reconfigure = ros_conv::ValidatedReconfigure<Config>;

 protected:
  std::unique_ptr<core::ObjectDetector> createDetector(const ros::NodeHandle& pnh) override {
    params_nh_ = ros::NodeHandle(pnh, Traits::kNamespace);
    loadFields(params_nh_, &params_);
    return std::make_unique<typename Traits::Detector>(params_);
  }

  void startReconfigure(const ros::NodeHandle& /*pnh*/) override {
    reconfigure_ =
        std::make_unique<Reconfigure>(params_nh_, ros_conv::toConfig<Config>(params_),
                                      [this](const Config& config) { return apply(config); });
  }

 private:
  std::string apply(const Config& config) {
    const Params p = ros_conv::fromConfig(config, params_);
    const std::string error = checkFields(params_nh_, p);
    if (!error.empty()) return error;
    replaceDetector(std::make_unique<typename Traits::Detector>(p),
                    std::make_unique<typename Traits::Detector>(p));  // the early chain's
    params_ = p;
    return "";
  }

  Params params_;              // in force
  ros::NodeHandle params_nh_;  // ~<Traits::kNamespace>
  std::unique_ptr<Reconfigure> reconfigure_;
};

}  // namespace ros_conv
}  // namespace urban_detection
