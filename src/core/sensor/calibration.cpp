// Calibration readers (velodyne_pointcloud YAML, Velodyne db.xml) and the nominal geometry.
//
// Both file formats describe the same per-laser correction model; the YAML stores SI units
// (radians, metres) while db.xml stores degrees and centimetres, so the XML reader converts.
#include "urban_detection/core/sensor/calibration.h"

#include <sys/stat.h>
#include <tinyxml2.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace urban_detection {
namespace core {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr double kCmToM = 0.01;

std::string laserLabel(int index, int laser_id) {
  std::ostringstream s;
  s << "laser " << laser_id;
  if (index != laser_id) s << " (entry #" << index << ")";
  return s.str();
}

[[noreturn]] void fail(const std::string& file, const std::string& where, const std::string& what) {
  std::string msg = "calibration '" + file + "'";
  if (!where.empty()) msg += ": " + where;
  msg += ": " + what;
  throw CalibrationError(msg);
}

// ----------------------------------------------------------------------------------------------
// YAML

double yamlDouble(const YAML::Node& node, const std::string& file, const std::string& where,
                  const std::string& field) {
  try {
    return node.as<double>();
  } catch (const YAML::Exception&) {
    std::string text = node.IsScalar() ? node.Scalar() : std::string("<non-scalar>");
    fail(file, where, "field '" + field + "' is not a number (got '" + text + "')");
  }
}

int yamlInt(const YAML::Node& node, const std::string& file, const std::string& where,
            const std::string& field) {
  const double v = yamlDouble(node, file, where, field);
  if (!std::isfinite(v) || v != std::floor(v) || std::fabs(v) > 1e6) {
    fail(file, where, "field '" + field + "' must be an integer (got '" + node.Scalar() + "')");
  }
  return static_cast<int>(v);
}

bool yamlBool(const YAML::Node& node, const std::string& file, const std::string& where,
              const std::string& field) {
  try {
    return node.as<bool>();
  } catch (const YAML::Exception&) {
    // velodyne_pointcloud files sometimes write 0/1.
    const std::string s = node.IsScalar() ? node.Scalar() : std::string("<non-scalar>");
    if (s == "0") return false;
    if (s == "1") return true;
    fail(file, where, "field '" + field + "' is not a boolean (got '" + s + "')");
  }
}

double requiredDouble(const YAML::Node& laser, const char* field, const std::string& file,
                      const std::string& where) {
  const YAML::Node n = laser[field];
  if (!n) fail(file, where, std::string("missing field '") + field + "'");
  return yamlDouble(n, file, where, field);
}

double optionalDouble(const YAML::Node& laser, const char* field, double fallback,
                      const std::string& file, const std::string& where) {
  const YAML::Node n = laser[field];
  return n ? yamlDouble(n, file, where, field) : fallback;
}

// ----------------------------------------------------------------------------------------------
// db.xml

const tinyxml2::XMLElement* xmlChild(const tinyxml2::XMLElement* parent, const char* name,
                                     const std::string& file, const std::string& where) {
  const tinyxml2::XMLElement* e = parent->FirstChildElement(name);
  if (e == nullptr) fail(file, where, std::string("missing element '") + name + "'");
  return e;
}

double xmlDouble(const tinyxml2::XMLElement* e, const std::string& file, const std::string& where,
                 const std::string& field) {
  const char* text = e->GetText();
  if (text == nullptr) fail(file, where, "field '" + field + "' is empty");
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  while (end != nullptr && *end != '\0' && std::isspace(static_cast<unsigned char>(*end))) ++end;
  if (end == text || (end != nullptr && *end != '\0')) {
    fail(file, where, "field '" + field + "' is not a number (got '" + text + "')");
  }
  return v;
}

double xmlRequired(const tinyxml2::XMLElement* px, const char* name, const std::string& file,
                   const std::string& where) {
  return xmlDouble(xmlChild(px, name, file, where), file, where, name);
}

// Reads a boost-serialised std::vector<int> (<count>, optional <item_version>, <item>...).
std::vector<double> xmlItemList(const tinyxml2::XMLElement* list, const std::string& file,
                                const std::string& name) {
  std::vector<double> out;
  int i = 0;
  for (const tinyxml2::XMLElement* it = list->FirstChildElement("item"); it != nullptr;
       it = it->NextSiblingElement("item"), ++i) {
    out.push_back(xmlDouble(it, file, name + " item " + std::to_string(i), name));
  }
  return out;
}

}  // namespace

// ------------------------------------------------------------------------------------------------
void Calibration::finalize() {
  const std::string& file = source;
  if (!std::isfinite(distance_resolution_m) || distance_resolution_m <= 0.0 ||
      distance_resolution_m > 0.1) {
    fail(file, "",
         "field 'distance_resolution' must be in (0, 0.1] m (got " +
             std::to_string(distance_resolution_m) + ")");
  }
  if (static_cast<int>(lasers.size()) != kNumLasers) {
    fail(file, "",
         "expected " + std::to_string(kNumLasers) + " lasers, found " +
             std::to_string(lasers.size()));
  }
  // Order by laser id, each id exactly once.
  std::vector<LaserCorrection> ordered(kNumLasers);
  std::vector<bool> seen(kNumLasers, false);
  for (std::size_t i = 0; i < lasers.size(); ++i) {
    const LaserCorrection& c = lasers[i];
    const std::string where = laserLabel(static_cast<int>(i), c.laser_id);
    if (c.laser_id < 0 || c.laser_id >= kNumLasers) {
      fail(file, where, "field 'laser_id' out of range 0.." + std::to_string(kNumLasers - 1));
    }
    if (seen[c.laser_id]) fail(file, where, "field 'laser_id' duplicated");
    seen[c.laser_id] = true;
    ordered[c.laser_id] = c;
  }
  lasers.swap(ordered);

  for (LaserCorrection& c : lasers) {
    const std::string where = laserLabel(c.laser_id, c.laser_id);
    auto check = [&](double v, const char* field, double lo, double hi) {
      if (!std::isfinite(v) || v < lo || v > hi) {
        std::ostringstream s;
        s << "field '" << field << "' = " << v << " outside [" << lo << ", " << hi << "]";
        fail(file, where, s.str());
      }
    };
    check(c.rot_correction_rad, "rot_correction", -kPi, kPi);
    check(c.vert_correction_rad, "vert_correction", -kPi / 4, kPi / 4);
    check(c.dist_correction_m, "dist_correction", -10.0, 10.0);
    check(c.dist_correction_x_m, "dist_correction_x", -10.0, 10.0);
    check(c.dist_correction_y_m, "dist_correction_y", -10.0, 10.0);
    check(c.vert_offset_correction_m, "vert_offset_correction", -1.0, 1.0);
    check(c.horiz_offset_correction_m, "horiz_offset_correction", -1.0, 1.0);
    check(c.focal_distance, "focal_distance", 0.0, 200.0);
    check(c.focal_slope, "focal_slope", -100.0, 100.0);
    check(c.min_intensity, "min_intensity", 0, 255);
    check(c.max_intensity, "max_intensity", 0, 255);
    if (c.min_intensity > c.max_intensity) {
      fail(file, where,
           "field 'min_intensity' (" + std::to_string(c.min_intensity) +
               ") exceeds 'max_intensity' (" + std::to_string(c.max_intensity) + ")");
    }
    c.cos_rot = std::cos(c.rot_correction_rad);
    c.sin_rot = std::sin(c.rot_correction_rad);
    c.cos_vert = std::cos(c.vert_correction_rad);
    c.sin_vert = std::sin(c.vert_correction_rad);
  }

  std::vector<int> by_angle(kNumLasers);
  for (int i = 0; i < kNumLasers; ++i) by_angle[i] = i;
  std::stable_sort(by_angle.begin(), by_angle.end(), [this](int a, int b) {
    return lasers[a].vert_correction_rad < lasers[b].vert_correction_rad;
  });
  ring_of_laser.assign(kNumLasers, 0);
  for (int rank = 0; rank < kNumLasers; ++rank) ring_of_laser[by_angle[rank]] = rank;
}

Calibration Calibration::nominalHdl64eS2() {
  // HDL-64E S2 datasheet: vertical field of view +2 deg to -24.8 deg in 64 equally spaced
  // subdivisions (~0.425 deg). The upper block (lasers 0-31) covers the top half, the lower
  // block (32-63) the bottom half, each from top to bottom. No rotational, distance or offset
  // corrections: a geometry to run without a file, not a substitute for a calibration.
  Calibration cal;
  cal.source = "nominal HDL-64E S2";
  cal.distance_resolution_m = 0.002;
  cal.lasers.resize(kNumLasers);
  const double top_deg = 2.0, bottom_deg = -24.8;
  const double step_deg = (top_deg - bottom_deg) / (kNumLasers - 1);
  for (int i = 0; i < kNumLasers; ++i) {
    LaserCorrection& c = cal.lasers[i];
    c.laser_id = i;
    c.vert_correction_rad = (top_deg - step_deg * i) * kDegToRad;
  }
  cal.finalize();
  return cal;
}

// ------------------------------------------------------------------------------------------------
namespace {
// Opening a FIFO would block until a writer comes and reading a directory fails deep inside a
// stream: both are refused first, naming the file.
void requireRegularFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) fail(path, "", "cannot open file");
  if (S_ISDIR(st.st_mode)) fail(path, "", "is a directory, not a calibration file");
  if (!S_ISREG(st.st_mode)) fail(path, "", "is not a regular file (a FIFO, device or socket)");
}
}  // namespace

Calibration loadCalibrationYaml(const std::string& path) {
  requireRegularFile(path);
  std::ifstream in(path);
  if (!in) fail(path, "", "cannot open file");
  YAML::Node root;
  try {
    root = YAML::Load(in);
  } catch (const YAML::Exception& e) {
    fail(path, "line " + std::to_string(e.mark.line + 1),
         std::string("YAML syntax error: ") + e.msg);
  }
  if (!root.IsMap()) fail(path, "", "top level is not a map");

  Calibration cal;
  cal.source = path;
  if (const YAML::Node n = root["distance_resolution"]) {
    cal.distance_resolution_m = yamlDouble(n, path, "", "distance_resolution");
  }
  const YAML::Node lasers = root["lasers"];
  if (!lasers) fail(path, "", "missing field 'lasers'");
  if (!lasers.IsSequence()) fail(path, "", "field 'lasers' is not a list");
  if (const YAML::Node n = root["num_lasers"]) {
    const int num = yamlInt(n, path, "", "num_lasers");
    if (num != static_cast<int>(lasers.size())) {
      fail(path, "",
           "field 'num_lasers' = " + std::to_string(num) + " but 'lasers' has " +
               std::to_string(lasers.size()) + " entries");
    }
  }

  for (std::size_t i = 0; i < lasers.size(); ++i) {
    const YAML::Node l = lasers[i];
    const std::string entry = "laser entry #" + std::to_string(i);
    if (!l.IsMap()) fail(path, entry, "is not a map");
    const YAML::Node id = l["laser_id"];
    if (!id) fail(path, entry, "missing field 'laser_id'");
    LaserCorrection c;
    c.laser_id = yamlInt(id, path, entry, "laser_id");
    const std::string where = laserLabel(static_cast<int>(i), c.laser_id);
    // Required by velodyne_pointcloud's reader.
    c.rot_correction_rad = requiredDouble(l, "rot_correction", path, where);
    c.vert_correction_rad = requiredDouble(l, "vert_correction", path, where);
    c.dist_correction_m = requiredDouble(l, "dist_correction", path, where);
    // Optional there, with these defaults.
    c.two_pt_correction_available =
        l["two_pt_correction_available"]
            ? yamlBool(l["two_pt_correction_available"], path, where, "two_pt_correction_available")
            : false;
    c.dist_correction_x_m = optionalDouble(l, "dist_correction_x", 0.0, path, where);
    c.dist_correction_y_m = optionalDouble(l, "dist_correction_y", 0.0, path, where);
    c.vert_offset_correction_m = optionalDouble(l, "vert_offset_correction", 0.0, path, where);
    c.horiz_offset_correction_m = optionalDouble(l, "horiz_offset_correction", 0.0, path, where);
    c.focal_distance = optionalDouble(l, "focal_distance", 0.0, path, where);
    c.focal_slope = optionalDouble(l, "focal_slope", 0.0, path, where);
    c.min_intensity =
        l["min_intensity"] ? yamlInt(l["min_intensity"], path, where, "min_intensity") : 0;
    c.max_intensity =
        l["max_intensity"] ? yamlInt(l["max_intensity"], path, where, "max_intensity") : 255;
    cal.lasers.push_back(c);
  }
  cal.finalize();
  return cal;
}

Calibration loadCalibrationDbXml(const std::string& path) {
  requireRegularFile(path);
  tinyxml2::XMLDocument doc;
  const tinyxml2::XMLError err = doc.LoadFile(path.c_str());
  if (err == tinyxml2::XML_ERROR_FILE_NOT_FOUND ||
      err == tinyxml2::XML_ERROR_FILE_COULD_NOT_BE_OPENED) {
    fail(path, "", "cannot open file");
  }
  if (err != tinyxml2::XML_SUCCESS) {
    fail(path, "line " + std::to_string(doc.ErrorLineNum()),
         std::string("XML syntax error: ") + doc.ErrorStr());
  }
  // boost::serialization layout: <boost_serialization><DB>...</DB></boost_serialization>.
  const tinyxml2::XMLElement* root = doc.FirstChildElement("boost_serialization");
  const tinyxml2::XMLElement* db =
      root != nullptr ? root->FirstChildElement("DB") : doc.FirstChildElement("DB");
  if (db == nullptr) fail(path, "", "missing element 'DB'");

  Calibration cal;
  cal.source = path;
  cal.distance_resolution_m = xmlRequired(db, "distLSB_", path, "DB") * kCmToM;

  const tinyxml2::XMLElement* points = xmlChild(db, "points_", path, "DB");
  std::vector<double> min_i, max_i;
  if (const tinyxml2::XMLElement* e = db->FirstChildElement("minIntensity_")) {
    min_i = xmlItemList(e, path, "minIntensity_");
  }
  if (const tinyxml2::XMLElement* e = db->FirstChildElement("maxIntensity_")) {
    max_i = xmlItemList(e, path, "maxIntensity_");
  }

  int index = 0;
  for (const tinyxml2::XMLElement* item = points->FirstChildElement("item"); item != nullptr;
       item = item->NextSiblingElement("item"), ++index) {
    const std::string entry = "points_ item #" + std::to_string(index);
    const tinyxml2::XMLElement* px = xmlChild(item, "px", path, entry);
    LaserCorrection c;
    const double id = xmlRequired(px, "id_", path, entry);
    // Range before the cast: converting inf, NaN or 1e300 to int is undefined behaviour.
    if (!(id >= 0.0 && id < kNumLasers) || id != std::floor(id)) {
      fail(path, entry,
           "field 'id_' must be an integer in 0.." + std::to_string(kNumLasers - 1) + " (got " +
               xmlChild(px, "id_", path, entry)->GetText() + ")");
    }
    c.laser_id = static_cast<int>(id);
    const std::string where = laserLabel(index, c.laser_id);
    c.rot_correction_rad = xmlRequired(px, "rotCorrection_", path, where) * kDegToRad;
    c.vert_correction_rad = xmlRequired(px, "vertCorrection_", path, where) * kDegToRad;
    c.dist_correction_m = xmlRequired(px, "distCorrection_", path, where) * kCmToM;
    const tinyxml2::XMLElement* dx = px->FirstChildElement("distCorrectionX_");
    const tinyxml2::XMLElement* dy = px->FirstChildElement("distCorrectionY_");
    // S2 and later databases carry the two-point near-range terms; older ones do not.
    c.two_pt_correction_available = dx != nullptr && dy != nullptr;
    if (dx != nullptr)
      c.dist_correction_x_m = xmlDouble(dx, path, where, "distCorrectionX_") * kCmToM;
    if (dy != nullptr)
      c.dist_correction_y_m = xmlDouble(dy, path, where, "distCorrectionY_") * kCmToM;
    c.vert_offset_correction_m = xmlRequired(px, "vertOffsetCorrection_", path, where) * kCmToM;
    if (const tinyxml2::XMLElement* e = px->FirstChildElement("horizOffsetCorrection_")) {
      c.horiz_offset_correction_m = xmlDouble(e, path, where, "horizOffsetCorrection_") * kCmToM;
    }
    if (const tinyxml2::XMLElement* e = px->FirstChildElement("focalDistance_")) {
      c.focal_distance = xmlDouble(e, path, where, "focalDistance_") * kCmToM;
    }
    if (const tinyxml2::XMLElement* e = px->FirstChildElement("focalSlope_")) {
      c.focal_slope = xmlDouble(e, path, where, "focalSlope_");
    }
    // Intensity limits are separate arrays indexed by laser id. Range before the cast (an
    // item of 1e20 or nan must not reach static_cast<int>).
    auto intensity = [&](const std::vector<double>& list, const char* name, int* out) {
      if (c.laser_id >= static_cast<int>(list.size())) return;
      const double v = list[c.laser_id];
      if (!(v >= 0.0 && v <= 255.0) || v != std::floor(v)) {
        std::ostringstream s;
        s << "field '" << name << "' item " << c.laser_id << " must be an integer in 0..255 (got "
          << v << ")";
        fail(path, where, s.str());
      }
      *out = static_cast<int>(v);
    };
    intensity(min_i, "minIntensity_", &c.min_intensity);
    intensity(max_i, "maxIntensity_", &c.max_intensity);
    cal.lasers.push_back(c);
  }
  cal.finalize();
  return cal;
}

Calibration loadCalibration(const std::string& path) {
  if (path.empty()) return Calibration::nominalHdl64eS2();
  std::string ext;
  const std::size_t dot = path.find_last_of('.');
  if (dot != std::string::npos) ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  if (ext == "yaml" || ext == "yml") return loadCalibrationYaml(path);
  if (ext == "xml") return loadCalibrationDbXml(path);
  fail(path, "", "unknown calibration format (expected .yaml, .yml or .xml)");
}

}  // namespace core
}  // namespace urban_detection
