// Regression tests for bugs found by the libFuzzer targets of test/fuzz. Each test
// names the target that found the bug; the crashing input is kept in that target's seed
// corpus (test/fuzz/corpus/<target>/crash-*) so the fuzzers replay it too.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "test_files.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/hdl64e_packet.h"
#include "urban_detection/core/sensor/pcap_io.h"

namespace uc = urban_detection::core;

namespace {

using ud_test::TempFile;

// A valid 64-laser db.xml whose laser 5 gets `id5` as its id_ text, followed by an intensity
// list whose item 7 is `min7`.
std::string dbXml(const std::string& id5, const std::string& min7) {
  std::ostringstream s;
  s << "<?xml version=\"1.0\"?>\n<boost_serialization><DB><distLSB_>0.2</distLSB_>\n"
       "<points_><count>64</count>\n";
  for (int l = 0; l < uc::kNumLasers; ++l) {
    s << "<item><px><id_>" << (l == 5 ? id5 : std::to_string(l)) << "</id_>"
      << "<rotCorrection_>0</rotCorrection_><vertCorrection_>" << (2.0 - 0.4 * l)
      << "</vertCorrection_><distCorrection_>0</distCorrection_>"
      << "<vertOffsetCorrection_>0</vertOffsetCorrection_></px></item>\n";
  }
  s << "</points_>\n<minIntensity_><count>64</count>";
  for (int l = 0; l < uc::kNumLasers; ++l) s << "<item>" << (l == 7 ? min7 : "0") << "</item>";
  s << "</minIntensity_>\n</DB></boost_serialization>\n";
  return s.str();
}

std::string errorOf(const std::string& path) {
  try {
    uc::loadCalibration(path);
  } catch (const uc::CalibrationError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// fuzz_calibration_xml: an id_ of inf / 1e300 passed the integer test (inf == floor(inf)) and
// was converted to int (undefined behaviour; UBSan: "inf is outside the range of int").
TEST(FuzzRegressions, DbXmlLaserIdOutsideIntRangeIsRejectedByName) {
  const TempFile good(".xml", dbXml("5", "0"));
  EXPECT_EQ(errorOf(good.path()), "");  // the base file is valid
  for (const char* id : {"inf", "-inf", "1e300", "-3e9", "nan", "64", "-1", "4.5"}) {
    const TempFile f(".xml", dbXml(id, "0"));
    const std::string msg = errorOf(f.path());
    EXPECT_NE(msg.find(f.path()), std::string::npos) << id << ": " << msg;
    EXPECT_NE(msg.find("points_ item #5"), std::string::npos) << id << ": " << msg;
    EXPECT_NE(msg.find("'id_' must be an integer in 0..63"), std::string::npos)
        << id << ": " << msg;
  }
}

// fuzz_calibration_xml: an intensity list item of 1e20 or nan was converted to int before any
// range check (undefined behaviour).
TEST(FuzzRegressions, DbXmlIntensityItemOutsideByteRangeIsRejectedByName) {
  const TempFile good(".xml", dbXml("5", "17"));
  ASSERT_EQ(errorOf(good.path()), "");
  EXPECT_EQ(uc::loadCalibration(good.path()).lasers[7].min_intensity, 17);
  for (const char* v : {"1e20", "-1e20", "nan", "inf", "256", "-1", "2.5"}) {
    const TempFile f(".xml", dbXml("5", v));
    const std::string msg = errorOf(f.path());
    EXPECT_NE(msg.find("laser 7"), std::string::npos) << v << ": " << msg;
    EXPECT_NE(msg.find("'minIntensity_' item 7 must be an integer in 0..255"), std::string::npos)
        << v << ": " << msg;
  }
}

// fuzz_pcap_reader: after a corrupt record header libpcap reports an error (kTruncated) but
// leaves the file positioned inside the record, so a further next() parsed the record's
// payload as headers and could return a packet although kTruncated promises that nothing
// more can be read. The corrupt header here is followed by a whole valid record, which the
// old reader returned on the second call.
TEST(FuzzRegressions, PcapReaderStaysTruncatedAfterACorruptRecordHeader) {
  const std::string valid_path = ud_test::tempPath("fuzzreg_valid.pcap");
  {
    uc::PcapWriter writer(valid_path);
    uc::RawPacket packet{};
    for (int b = 0; b < uc::kBlocksPerPacket; ++b) {
      packet[100 * b] = 0xFF;
      packet[100 * b + 1] = b % 2 == 0 ? 0xEE : 0xDD;
    }
    writer.write(packet, 1.5e9);
  }
  std::ifstream in(valid_path, std::ios::binary);
  const std::vector<char> valid((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  std::remove(valid_path.c_str());
  ASSERT_GT(valid.size(), 24u + 16u + 1206u);
  // Global header, then a record header claiming 2 GB (libpcap rejects > 256 kB), then the
  // valid record.
  std::string bytes(valid.begin(), valid.begin() + 24);
  const std::uint32_t bogus[4] = {1500000000u, 0u, 0x7FFFFFFFu, 0x7FFFFFFFu};
  bytes.append(reinterpret_cast<const char*>(bogus), sizeof bogus);
  bytes.append(valid.begin() + 24, valid.end());
  const TempFile f(".pcap", bytes);

  uc::PcapReader reader(f.path());
  uc::PcapPacket packet;
  EXPECT_EQ(reader.next(&packet), uc::PcapReader::Result::kTruncated);
  EXPECT_EQ(reader.next(&packet), uc::PcapReader::Result::kTruncated);  // was kPacket
  EXPECT_EQ(reader.next(&packet), uc::PcapReader::Result::kTruncated);
  reader.rewind();  // starts over: the same outcome
  EXPECT_EQ(reader.next(&packet), uc::PcapReader::Result::kTruncated);

  // Control: the valid capture alone gives its packet, then a lasting end.
  const TempFile ok(".pcap", std::string(valid.begin(), valid.end()));
  uc::PcapReader good(ok.path());
  EXPECT_EQ(good.next(&packet), uc::PcapReader::Result::kPacket);
  EXPECT_EQ(good.next(&packet), uc::PcapReader::Result::kEnd);
  EXPECT_EQ(good.next(&packet), uc::PcapReader::Result::kEnd);
}
