#include "urban_detection/ros/param_loading.h"

namespace urban_detection {
namespace ros_conv {
namespace {

// NodeHandle::getParam() returns false both for "not set" and for "set with another type";
// telling the two apart lets a typo such as `port: "2368"` fail loudly instead of being ignored.
template <typename T>
void readOptional(const ros::NodeHandle& nh, const std::string& name, T* value,
                  const char* type_name) {
  if (!nh.hasParam(name)) return;
  if (!nh.getParam(name, *value)) {
    throw ParamError("parameter '" + nh.resolveName(name) + "' must be " + type_name);
  }
}

}  // namespace

void loadParam(const ros::NodeHandle& nh, const std::string& name, double* value) {
  readOptional(nh, name, value, "a number");
}

void loadParam(const ros::NodeHandle& nh, const std::string& name, int* value) {
  readOptional(nh, name, value, "an integer");
}

void loadParam(const ros::NodeHandle& nh, const std::string& name, bool* value) {
  readOptional(nh, name, value, "a boolean");
}

void loadParam(const ros::NodeHandle& nh, const std::string& name, std::string* value) {
  readOptional(nh, name, value, "a string");
}

void loadParam(const ros::NodeHandle& nh, const std::string& name, std::vector<double>* value) {
  readOptional(nh, name, value, "a list of numbers");
}

void loadParam(const ros::NodeHandle& nh, const std::string& name,
               std::vector<std::string>* value) {
  readOptional(nh, name, value, "a list of strings");
}

}  // namespace ros_conv
}  // namespace urban_detection
