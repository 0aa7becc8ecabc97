// Writes the seed corpora of the fuzz targets into <out>/<target>/ (usually
// test/fuzz/corpus): real-looking packets from the core encoder, captures from the core pcap
// writer (plus hand-built Linux-cooked, raw-IP and VLAN captures), calibrations in both file
// formats, serialised VelodyneScan messages and small structured clouds. Deterministic, so the
// committed seeds can be regenerated bit for bit: make_seeds <out>.
#include <sys/stat.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/pcap_io.h"
#if UD_HAVE_MSGS
#include <ros/serialization.h>
#include <urban_detection/VelodyneScan.h>
#endif

namespace core = urban_detection::core;
using Bytes = std::vector<std::uint8_t>;

namespace {

std::string g_out;

void put(const std::string& target, const std::string& name, const Bytes& bytes) {
  const std::string dir = g_out + "/" + target;
  ::mkdir(g_out.c_str(), 0755);
  ::mkdir(dir.c_str(), 0755);
  std::FILE* f = std::fopen((dir + "/" + name).c_str(), "wb");
  if (f == nullptr) {
    std::perror(dir.c_str());
    std::exit(1);
  }
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
}
void put(const std::string& target, const std::string& name, const std::string& text) {
  put(target, name, Bytes(text.begin(), text.end()));
}
void append(Bytes* b, const void* p, std::size_t n) {
  const auto* c = static_cast<const std::uint8_t*>(p);
  b->insert(b->end(), c, c + n);
}
void le16(Bytes* b, std::uint16_t v) {
  append(b, &v, 2);
}  // x86: little endian
void le32(Bytes* b, std::uint32_t v) {
  append(b, &v, 4);
}
Bytes readFile(const std::string& path) {
  Bytes b;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return b;
  std::uint8_t buf[4096];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) b.insert(b.end(), buf, buf + n);
  std::fclose(f);
  return b;
}

// Firings of a plausible street: ground rings, a wall at 15 m on the left, gaps (no return).
core::RawPacket streetPacket(const core::PacketEncoder& enc, std::uint16_t first_azimuth,
                             std::uint16_t step, std::uint32_t ts) {
  core::Firing f[6];
  for (int k = 0; k < 6; ++k) {
    f[k].azimuth = static_cast<std::uint16_t>((first_azimuth + k * step) % 36000);
    for (int l = 0; l < core::kNumLasers; ++l) {
      const double elev = enc.calibration().lasers[l].vert_correction_rad;
      double range = elev < -0.01 ? 1.73 / std::sin(-elev) : 15.0 + 0.1 * l;
      if (range > 120.0 || (l + k) % 11 == 0) range = 0.0;  // no return
      f[k].distance[l] = static_cast<std::uint16_t>(range / 0.002);
      f[k].intensity[l] = static_cast<std::uint8_t>(20 + 3 * l);
    }
  }
  return enc.encode(f, ts);
}

void packetSeeds(const core::PacketEncoder& enc) {
  const std::string t = "fuzz_packet_decoder";
  const core::RawPacket p = streetPacket(enc, 100, 9, 1000);
  Bytes one{0};
  append(&one, p.data(), p.size());
  put(t, "single_valid", one);
  put(t, "single_truncated", Bytes(one.begin(), one.begin() + 601));
  Bytes dual = one;  // two upper blocks at the same azimuth: dual-return packet
  std::memcpy(dual.data() + 1 + 200 + 2, dual.data() + 1 + 2, 2);
  put(t, "single_dual_return", dual);
  // Mode 1: three datagrams (valid, short, valid) crossing azimuth 0.
  Bytes stream{1, 0, 0};
  const core::RawPacket a = streetPacket(enc, 35900, 9, 2000), b = streetPacket(enc, 50, 9, 2288);
  le16(&stream, core::kPacketSize);
  append(&stream, a.data(), a.size());
  le16(&stream, 40);
  append(&stream, a.data(), 40);
  le16(&stream, core::kPacketSize);
  append(&stream, b.data(), b.size());
  put(t, "stream_cut", stream);
  // Mode 2: template packets around a whole turn, cut at 90 deg.
  Bytes tpl{2};
  const float cut = 90.0f;
  append(&tpl, &cut, 4);
  for (int k = 0; k < 8; ++k) {
    le16(&tpl, static_cast<std::uint16_t>(k * 4600));
    tpl.push_back(9);
    tpl.push_back(0);
    for (int j = 0; j < 384; ++j) tpl.push_back(static_cast<std::uint8_t>(10 + 7 * (j % 32) + k));
  }
  put(t, "template_turn", tpl);
}

void pcapSeeds(const core::PacketEncoder& enc) {
  const std::string t = "fuzz_pcap_reader";
  const std::string tmp = g_out + "/.tmp.pcap";
  {
    core::PcapWriter w(tmp);
    for (int k = 0; k < 3; ++k)
      w.write(streetPacket(enc, 35000 + 400 * k, 9, 5000 + 288 * k), 1.5e9 + k * 288e-6);
  }
  const Bytes eth = readFile(tmp);
  std::remove(tmp.c_str());
  put(t, "ethernet_3", eth);
  put(t, "ethernet_truncated", Bytes(eth.begin(), eth.end() - 500));

  // Hand-built captures of the other link types the reader parses.
  const core::RawPacket p = streetPacket(enc, 1200, 9, 7000);
  auto ipUdp = [&](Bytes* b) {
    const std::uint8_t ip[20] = {0x45, 0, 0x04, 0xD2, 0, 0,  0x40, 0,   64,  17,
                                 0,    0, 192,  168,  3, 43, 255,  255, 255, 255};  // total 1234
    append(b, ip, 20);
    const std::uint8_t udp[8] = {0x09, 0x40, 0x09, 0x40, 0x04, 0xBE, 0, 0};  // 2368, len 1214
    append(b, udp, 8);
    append(b, p.data(), p.size());
  };
  auto capture = [&](std::uint32_t linktype, const Bytes& frame) {
    Bytes b;
    le32(&b, 0xA1B2C3D4);
    le16(&b, 2);
    le16(&b, 4);
    le32(&b, 0);
    le32(&b, 0);
    le32(&b, 65535);
    le32(&b, linktype);
    for (int k = 0; k < 2; ++k) {
      le32(&b, 1500000000u + k);
      le32(&b, 1000u * k);
      le32(&b, static_cast<std::uint32_t>(frame.size()));
      le32(&b, static_cast<std::uint32_t>(frame.size()));
      append(&b, frame.data(), frame.size());
    }
    return b;
  };
  Bytes sll = {0, 0, 0, 1, 0, 6, 0x60, 0x76, 0x88, 0, 0, 1, 0, 0, 0x08, 0x00};
  ipUdp(&sll);
  put(t, "linux_sll", capture(113, sll));
  Bytes raw;
  ipUdp(&raw);
  put(t, "raw_ipv4", capture(101, raw));
  Bytes vlan = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x60, 0x76, 0x88,
                0,    0,    1,    0x81, 0x00, 0x00, 0x05, 0x08, 0x00};
  ipUdp(&vlan);
  put(t, "ethernet_vlan", capture(1, vlan));
}

std::string yamlOf(const core::Calibration& cal, bool two_pt) {
  std::ostringstream s;
  s.precision(10);
  s << "distance_resolution: " << cal.distance_resolution_m << "\nnum_lasers: 64\nlasers:\n";
  for (const core::LaserCorrection& c : cal.lasers) {
    s << "- {laser_id: " << c.laser_id << ", rot_correction: " << c.rot_correction_rad
      << ", vert_correction: " << c.vert_correction_rad
      << ", dist_correction: " << c.dist_correction_m;
    if (two_pt) {
      s << ", dist_correction_x: " << c.dist_correction_x_m
        << ", dist_correction_y: " << c.dist_correction_y_m
        << ", two_pt_correction_available: true, vert_offset_correction: "
        << c.vert_offset_correction_m
        << ", horiz_offset_correction: " << c.horiz_offset_correction_m
        << ", focal_distance: " << c.focal_distance << ", focal_slope: " << c.focal_slope
        << ", min_intensity: " << c.min_intensity << ", max_intensity: " << c.max_intensity;
    }
    s << "}\n";
  }
  return s.str();
}

std::string xmlOf(const core::Calibration& cal, bool intensities) {
  constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;
  std::ostringstream s;
  s.precision(10);
  s << "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\" ?>\n"
       "<!DOCTYPE boost_serialization>\n<boost_serialization signature=\"serialization::archive\" "
       "version=\"4\">\n<DB class_id=\"0\" tracking_level=\"0\" version=\"0\">\n"
    << "<distLSB_>" << cal.distance_resolution_m * 100 << "</distLSB_>\n<points_>\n"
    << "<count>64</count><item_version>1</item_version>\n";
  for (const core::LaserCorrection& c : cal.lasers) {
    s << "<item><px><id_>" << c.laser_id << "</id_><rotCorrection_>"
      << c.rot_correction_rad * kRadToDeg << "</rotCorrection_><vertCorrection_>"
      << c.vert_correction_rad * kRadToDeg << "</vertCorrection_><distCorrection_>"
      << c.dist_correction_m * 100 << "</distCorrection_><distCorrectionX_>"
      << c.dist_correction_x_m * 100 << "</distCorrectionX_><distCorrectionY_>"
      << c.dist_correction_y_m * 100 << "</distCorrectionY_><vertOffsetCorrection_>"
      << c.vert_offset_correction_m * 100 << "</vertOffsetCorrection_><horizOffsetCorrection_>"
      << c.horiz_offset_correction_m * 100 << "</horizOffsetCorrection_><focalDistance_>"
      << c.focal_distance * 100 << "</focalDistance_><focalSlope_>" << c.focal_slope
      << "</focalSlope_></px></item>\n";
  }
  s << "</points_>\n";
  if (intensities) {
    for (const char* list : {"minIntensity_", "maxIntensity_"}) {
      s << "<" << list << "><count>64</count>";
      for (const core::LaserCorrection& c : cal.lasers) {
        s << "<item>" << (list[1] == 'i' ? c.min_intensity : c.max_intensity) << "</item>";
      }
      s << "</" << list << ">\n";
    }
  }
  s << "</DB>\n</boost_serialization>\n";
  return s.str();
}

core::Calibration s2Like() {
  core::Calibration cal = core::Calibration::nominalHdl64eS2();
  for (int i = 0; i < core::kNumLasers; ++i) {
    core::LaserCorrection& c = cal.lasers[i];
    c.rot_correction_rad = -0.08 + 0.0025 * i;
    c.dist_correction_m = 1.35 + 0.002 * (i % 7);
    c.dist_correction_x_m = 1.40;
    c.dist_correction_y_m = 1.38;
    c.vert_offset_correction_m = i < 32 ? 0.215 : 0.155;
    c.horiz_offset_correction_m = (i % 2 == 0) ? 0.026 : -0.026;
    c.focal_distance = 10.5;
    c.focal_slope = 1.2;
    c.min_intensity = i % 5;
    c.max_intensity = 250 + i % 6;
  }
  cal.finalize();
  return cal;
}

void calibrationSeeds() {
  const core::Calibration nominal = core::Calibration::nominalHdl64eS2(), s2 = s2Like();
  put("fuzz_calibration_yaml", "nominal.yaml", yamlOf(nominal, false));
  put("fuzz_calibration_yaml", "s2_two_point.yaml", yamlOf(s2, true));
  std::string bad = yamlOf(s2, true);
  bad.replace(bad.find("laser_id: 5,"), 12, "laser_id: 4,");  // duplicated id
  put("fuzz_calibration_yaml", "duplicate_id.yaml", bad);
  put("fuzz_calibration_xml", "nominal.xml", xmlOf(nominal, false));
  put("fuzz_calibration_xml", "s2_intensities.xml", xmlOf(s2, true));
}

#if UD_HAVE_MSGS
void scanSeeds(const core::PacketEncoder& enc) {
  namespace ser = ros::serialization;
  for (int variant = 0; variant < 2; ++variant) {
    urban_detection::VelodyneScan scan;
    scan.header.seq = 7;
    scan.header.stamp = ros::Time(1500000000, 5000);
    scan.header.frame_id = "velodyne";
    const int n = variant == 0 ? 2 : 3;
    for (int k = 0; k < n; ++k) {
      urban_detection::VelodynePacket p;
      p.stamp = ros::Time(1500000000, 5000 + 288000 * k);
      const core::RawPacket raw = streetPacket(enc, 35800 + 150 * k, 9, 5000 + 288 * k);
      std::memcpy(p.data.data(), raw.data(), raw.size());
      if (variant == 1 && k == 1) p.data[0] = 0x12;  // a bad block id in the middle
      scan.packets.push_back(p);
    }
    Bytes b(ser::serializationLength(scan));
    ser::OStream out(b.data(), static_cast<std::uint32_t>(b.size()));
    ser::serialize(out, scan);
    put("fuzz_velodyne_scan", variant == 0 ? "two_packets" : "three_one_bad", b);
  }
}
#endif

void cloudSeeds() {
  const std::string t = "fuzz_cloud_stages";
  auto point = [](Bytes* b, std::uint8_t mode, int x, int y, int z) {
    b->push_back(mode);
    le16(b, static_cast<std::uint16_t>(static_cast<std::int16_t>(x)));
    le16(b, static_cast<std::uint16_t>(static_cast<std::int16_t>(y)));
    le16(b, static_cast<std::uint16_t>(static_cast<std::int16_t>(z)));
  };
  // Street in centimetres: ground rings, a car-sized box at (8, 3), a wall at y = -6, and
  // non-finite and huge points in between.
  Bytes street{0, 0};
  for (int r = 4; r <= 20; r += 2) {
    for (int a = 0; a < 36; ++a) {
      const double ang = a * 10.0 * 3.14159265 / 180.0;
      point(&street, 0, static_cast<int>(r * 100 * std::cos(ang)),
            static_cast<int>(r * 100 * std::sin(ang)), -173);
    }
  }
  for (int x = 700; x <= 1100; x += 20) {
    for (int z = -140; z <= -30; z += 15) point(&street, 0, x, 200, z);
  }
  for (int x = -1500; x <= 1500; x += 25) {
    for (int z = -170; z <= 300; z += 40) point(&street, 0, x, -600, z);
  }
  point(&street, 0x2A, 0, 1, 2);  // NaN, +inf, -inf specials
  point(&street, 0x2A, 3, 4, 5);  // +-1e30, FLT_MAX
  put(t, "street", street);
  // One cell holding everything, replicated by flag bit 0.
  Bytes blob{1, 1};
  for (int k = 0; k < 20; ++k) point(&blob, 0, 500 + k % 3, 500, -100 + k);
  put(t, "one_cell", blob);
  Bytes specials{3, 0};
  for (int k = 0; k < 16; ++k) point(&specials, 0x2A, k, k + 1, k + 2);
  put(t, "specials", specials);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_seeds <corpus dir>\n");
    return 2;
  }
  g_out = argv[1];
  const core::PacketEncoder enc(core::Calibration::nominalHdl64eS2());
  packetSeeds(enc);
  pcapSeeds(enc);
  calibrationSeeds();
#if UD_HAVE_MSGS
  scanSeeds(enc);
#endif
  cloudSeeds();
  return 0;
}
