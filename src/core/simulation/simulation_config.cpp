#include "urban_detection/core/simulation/simulation_config.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "urban_detection/core/params/field_yaml.h"

namespace urban_detection {
namespace core {

std::string validate(const SimulationConfig& c) {
  const std::string range = checkFieldRanges(c);
  if (!range.empty()) return range;
  try {
    validate(c.scene);
    validate(c.drive);
    validate(c.sensor);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

SimulationConfig parseSimulationConfig(const std::string& yaml_text,
                                       const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(source_name + ": YAML syntax error: " + e.what());
  }
  if (root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  SimulationConfig config;
  std::string error;
  if (!applyFieldsYaml(root, source_name + ": ", &config, &error)) {
    throw std::invalid_argument(error);
  }
  return config;
}

SimulationConfig loadSimulationConfig(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path + ": cannot open simulation config");
  std::stringstream ss;
  ss << in.rdbuf();
  SimulationConfig c = parseSimulationConfig(ss.str(), path);
  if (!c.calibration_file.empty() && c.calibration_file.front() != '/') {
    const std::size_t slash = path.find_last_of('/');
    if (slash != std::string::npos)
      c.calibration_file = path.substr(0, slash + 1) + c.calibration_file;
  }
  return c;
}

}  // namespace core
}  // namespace urban_detection
