#include "urban_detection/core/sweep_file.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace urban_detection {
namespace core {
namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string readBin(const std::string& path, CloudXYZIRT* cloud) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return "cannot open " + path;
  const std::streamsize bytes = in.tellg();
  if (bytes % 16 != 0) return path + ": size is not a multiple of 16 bytes (x y z r float32)";
  std::vector<float> buf(static_cast<std::size_t>(bytes / 4));
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(buf.data()), bytes)) return "cannot read " + path;
  cloud->points.resize(buf.size() / 4);
  for (std::size_t i = 0; i < cloud->points.size(); ++i) {
    PointXYZIRT& p = cloud->points[i];
    p.x = buf[4 * i];
    p.y = buf[4 * i + 1];
    p.z = buf[4 * i + 2];
    p.intensity = buf[4 * i + 3] * 255.0f;
    p.ring = 0;
    p.time = 0.0f;
  }
  return "";
}

std::string readPcd(const std::string& path, CloudXYZIRT* cloud) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "cannot open " + path;
  std::vector<std::string> fields;
  std::vector<int> sizes, counts;
  std::vector<char> types;
  long points = -1;
  std::string data, line;
  while (data.empty() && std::getline(in, line)) {
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key == "FIELDS") {
      for (std::string f; ls >> f;) fields.push_back(f);
    } else if (key == "SIZE") {
      for (int v; ls >> v;) sizes.push_back(v);
    } else if (key == "TYPE") {
      for (char v; ls >> v;) types.push_back(v);
    } else if (key == "COUNT") {
      for (int v; ls >> v;) counts.push_back(v);
    } else if (key == "POINTS") {
      ls >> points;
    } else if (key == "DATA") {
      ls >> data;
    }
  }
  if (data.empty() || points < 0 || fields.empty() || sizes.size() != fields.size() ||
      types.size() != fields.size()) {
    return path + ": incomplete PCD header";
  }
  if (counts.empty()) counts.assign(fields.size(), 1);
  int off[4] = {-1, -1, -1, -1};  // x y z intensity: offset in floats (binary) / column
  int stride = 0, column = 0;
  for (std::size_t f = 0; f < fields.size(); ++f) {
    const char* names[4] = {"x", "y", "z", "intensity"};
    for (int k = 0; k < 4; ++k) {
      if (fields[f] == names[k]) {
        if (sizes[f] != 4 || types[f] != 'F' || counts[f] != 1) {
          return path + ": field " + fields[f] + " is not a float32 scalar";
        }
        off[k] = data == "ascii" ? column : stride;
      }
    }
    stride += sizes[f] * counts[f];
    column += counts[f];
  }
  if (off[0] < 0 || off[1] < 0 || off[2] < 0) return path + ": no x y z fields";
  if (points > 100000000L) return path + ": implausible POINTS " + std::to_string(points);
  cloud->points.resize(static_cast<std::size_t>(points));
  if (data == "binary") {
    std::vector<char> buf(static_cast<std::size_t>(points) * stride);
    // Read POINTS records, not the rest of the file: the files may carry padding at the end.
    if (!in.read(buf.data(), static_cast<std::streamsize>(buf.size()))) {
      cloud->points.clear();
      return path + ": truncated binary data";
    }
    for (long i = 0; i < points; ++i) {
      const char* rec = buf.data() + i * stride;
      float v[4] = {0, 0, 0, 0};
      for (int k = 0; k < 4; ++k) {
        if (off[k] >= 0) std::memcpy(&v[k], rec + off[k], 4);
      }
      PointXYZIRT& p = cloud->points[i];
      p.x = v[0];
      p.y = v[1];
      p.z = v[2];
      p.intensity = v[3];
      p.ring = 0;
      p.time = 0.0f;
    }
  } else if (data == "ascii") {
    for (long i = 0; i < points; ++i) {
      if (!std::getline(in, line)) {
        cloud->points.clear();
        return path + ": truncated ascii data";
      }
      std::istringstream ls(line);
      std::vector<float> cols;
      for (float v; ls >> v;) cols.push_back(v);
      float v[4] = {0, 0, 0, 0};
      for (int k = 0; k < 4; ++k) {
        if (off[k] >= 0 && off[k] < static_cast<int>(cols.size())) v[k] = cols[off[k]];
      }
      PointXYZIRT& p = cloud->points[i];
      p.x = v[0];
      p.y = v[1];
      p.z = v[2];
      p.intensity = v[3];
      p.ring = 0;
      p.time = 0.0f;
    }
  } else {
    cloud->points.clear();
    return path + ": unsupported DATA " + data + " (binary or ascii)";
  }
  return "";
}

}  // namespace

std::string readSweepFile(const std::string& path, CloudXYZIRT* cloud) {
  cloud->points.clear();
  std::string err;
  if (endsWith(path, ".bin")) {
    err = readBin(path, cloud);
  } else if (endsWith(path, ".pcd")) {
    err = readPcd(path, cloud);
  } else {
    err = path + ": unknown extension (.bin or .pcd)";
  }
  if (!err.empty()) cloud->points.clear();
  cloud->width = static_cast<std::uint32_t>(cloud->points.size());
  cloud->height = 1;
  cloud->is_dense = false;
  return err;
}

std::vector<std::string> listSweepFiles(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string p = e.path().string();
    if (e.is_regular_file() && (endsWith(p, ".bin") || endsWith(p, ".pcd"))) files.push_back(p);
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace core
}  // namespace urban_detection
