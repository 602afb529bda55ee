// NMEA 0183: the framer, the GGA/RMC/GST fields and the epoch assembly.
// The example sentences are the textbook ones with their published
// checksums (GGA *47, RMC *6A) and NovAtel's GST example (*6A), so the
// framer's checksum is checked against someone else's arithmetic.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "drivers/gnss/nmea_fix_assembler.hpp"
#include "drivers/gnss/nmea_framer.hpp"
#include "drivers/gnss/nmea_sentences.hpp"
#include "support/alloc_counter.hpp"
#include "support/gnss_bytes.hpp"

namespace rtfuse::drivers {
namespace gnss_nmea_test {

const char* kGga = "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n";
const char* kRmc = "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A\r\n";
const char* kGst = "$GPGST,172814.0,0.006,0.023,0.020,273.6,0.023,0.020,0.031*6A\r\n";

// A sentence body with its checksum, for the cases no textbook prints.
std::string sentence(const std::string& body) { return test::nmea_sentence(body); }

// Every sentence the framer completes from `bytes`, each byte stamped with its index.
std::vector<NmeaFramer::Sentence> frame(NmeaFramer& f, const std::string& bytes, std::vector<std::string>* texts) {
  std::vector<NmeaFramer::Sentence> out;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    NmeaFramer::Sentence s;
    if (f.push(static_cast<std::uint8_t>(bytes[i]), static_cast<TimeNs>(i), &s)) {
      out.push_back(s);
      texts->emplace_back(s.text);
    }
  }
  return out;
}

TEST(NmeaFramer, TextbookSentencesPassTheirPublishedChecksums) {
  NmeaFramer f;
  std::vector<std::string> texts;
  const std::string stream = std::string("noise") + kGga + kRmc + kGst;
  const auto s = frame(f, stream, &texts);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(texts[0], "GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,");
  EXPECT_EQ(s[0].stamp, 5);  // its "$", after the five bytes of noise
  EXPECT_EQ(f.stats().sentences, 3);
  EXPECT_EQ(f.stats().skipped_bytes, 5);  // the noise; the LFs of CR LF are not counted
  EXPECT_EQ(f.stats().bad_checksum, 0);
}

TEST(NmeaFramer, DamageIsCountedByKindAndTheNextSentenceStillComes) {
  NmeaFramer f;
  std::vector<std::string> texts;
  std::string bad = kGga;
  bad[10] = '6';  // one digit of the time changed: the checksum no longer holds
  const std::string no_sum = "$GPGGA,123519,4807.038,N\r\n";
  const std::string cut = "$GPGGA,1235";  // a receiver reset mid-sentence
  const std::string binary = std::string("$GPRMC,12") + '\xB5' + "b";
  const std::string overlong = "$GPTXT," + std::string(300, 'x') + "*00\r\n";
  frame(f, bad + no_sum + cut + kRmc + binary + overlong + "\n" + kGga, &texts);
  ASSERT_EQ(texts.size(), 2u);
  EXPECT_EQ(texts[0].substr(0, 5), "GPRMC");
  EXPECT_EQ(texts[1].substr(0, 5), "GPGGA");
  EXPECT_EQ(f.stats().bad_checksum, 1);
  EXPECT_EQ(f.stats().missing_checksum, 1);
  EXPECT_EQ(f.stats().cut, 2);  // the reset, and the binary byte
  EXPECT_EQ(f.stats().overlong, 1);
}

TEST(NmeaFramer, LowerCaseChecksumAndLfOnlyLinesAreAccepted) {
  NmeaFramer f;
  std::vector<std::string> texts;
  frame(f, "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6a\n", &texts);
  EXPECT_EQ(texts.size(), 1u);
}

NmeaFields fields_of(const std::string& body) {
  static std::string keep;  // the fields point into it
  keep = body;
  NmeaFields f;
  EXPECT_TRUE(split_nmea_fields(keep, &f));
  return f;
}

TEST(NmeaSentences, GgaGivesPositionQualityAndEllipsoidHeight) {
  const NmeaFields f = fields_of("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,");
  EXPECT_EQ(nmea_sentence_type(f), "GGA");
  NmeaGga g;
  const char* why = "";
  ASSERT_TRUE(parse_gga(f, &g, &why)) << why;
  EXPECT_EQ(g.utc_ms_of_day, (12 * 3600 + 35 * 60 + 19) * 1000);
  EXPECT_TRUE(g.has_position);
  EXPECT_NEAR(g.latitude_deg, 48.0 + 7.038 / 60.0, 1e-12);
  EXPECT_NEAR(g.longitude_deg, 11.0 + 31.0 / 60.0, 1e-12);
  EXPECT_EQ(g.quality, 1);
  EXPECT_EQ(g.satellites, 8);
  EXPECT_DOUBLE_EQ(g.hdop, 0.9);
  EXPECT_NEAR(g.altitude_msl_m + g.geoid_separation_m, 592.3, 1e-9);
}

TEST(NmeaSentences, SouthAndWestAreNegativeAndANoFixGgaHasNoPosition) {
  NmeaGga g;
  const char* why = "";
  ASSERT_TRUE(parse_gga(fields_of("GNGGA,000001.50,3352.1234,S,15112.5000,W,2,10,1.2,10.0,M,-20.5,M,,"), &g, &why));
  EXPECT_NEAR(g.latitude_deg, -(33.0 + 52.1234 / 60.0), 1e-12);
  EXPECT_NEAR(g.longitude_deg, -(151.0 + 12.5 / 60.0), 1e-12);
  EXPECT_EQ(g.utc_ms_of_day, 1500);
  EXPECT_NEAR(g.altitude_msl_m + g.geoid_separation_m, -10.5, 1e-12);
  ASSERT_TRUE(parse_gga(fields_of("GPGGA,123520.00,,,,,0,00,99.99,,,,,,"), &g, &why));
  EXPECT_FALSE(g.has_position);
  EXPECT_EQ(g.quality, 0);
}

TEST(NmeaSentences, ABadFieldIsNamed) {
  NmeaGga g;
  const char* why = "";
  EXPECT_FALSE(parse_gga(fields_of("GPGGA,123519,4807.038,X,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), &g, &why));
  EXPECT_STREQ(why, "GGA latitude");
  EXPECT_FALSE(parse_gga(fields_of("GPGGA,123519,4861.000,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), &g, &why));
  EXPECT_STREQ(why, "GGA latitude");  // 61 minutes
  EXPECT_FALSE(parse_gga(fields_of("GPGGA,123519,9100.000,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), &g, &why));
  EXPECT_STREQ(why, "GGA latitude");  // 91 degrees
  EXPECT_FALSE(parse_gga(fields_of("GPGGA,123519,4807.038,N,18100.000,E,1,08,0.9,545.4,M,46.9,M,,"), &g, &why));
  EXPECT_STREQ(why, "GGA longitude");
  EXPECT_FALSE(parse_gga(fields_of("GPGGA,253519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), &g, &why));
  EXPECT_STREQ(why, "GGA time");
  // The fuzzer's first finding (tests/fuzz/regressions/gnss): a time beyond
  // int converted to int.
  EXPECT_FALSE(parse_gga(fields_of("GPGGA,123544444444444444444444444444444444444444444444444444444444444444.0,4807.038,N,"
                                   "01131.000,E,1,08,0.9,545.4,M,46.9,M,,"),
                         &g, &why));
  EXPECT_STREQ(why, "GGA time");
  EXPECT_FALSE(parse_gga(fields_of("GPGGA,123519,4807.038,N,01131.000,E,1,08,nan,545.4,M,46.9,M,,"), &g, &why));
  EXPECT_STREQ(why, "GGA HDOP");
  EXPECT_FALSE(parse_gga(fields_of("GPGGA,123519,4807.038,N,,,1,08,0.9,545.4,M,46.9,M,,"), &g, &why));
  EXPECT_STREQ(why, "GGA position: latitude without longitude or the reverse");
}

TEST(NmeaSentences, RmcSpeedCourseAndModeAndGstSigmas) {
  NmeaRmc r;
  const char* why = "";
  ASSERT_TRUE(parse_rmc(fields_of("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W"), &r, &why));
  EXPECT_TRUE(r.valid);
  EXPECT_NEAR(r.speed_mps, 22.4 * 1852.0 / 3600.0, 1e-12);
  EXPECT_DOUBLE_EQ(r.course_deg, 84.4);
  EXPECT_EQ(r.mode, '\0');
  ASSERT_TRUE(parse_rmc(fields_of("GNRMC,123520.00,V,,,,,,,230394,,,E,V"), &r, &why));
  EXPECT_FALSE(r.valid);
  EXPECT_EQ(r.mode, 'E');
  EXPECT_FALSE(parse_rmc(fields_of("GPRMC,123519,Q,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W"), &r, &why));
  EXPECT_STREQ(why, "RMC status");
  NmeaGst g;
  ASSERT_TRUE(parse_gst(fields_of("GPGST,172814.0,0.006,0.023,0.020,273.6,0.023,0.020,0.031"), &g, &why));
  EXPECT_DOUBLE_EQ(g.sigma_latitude_m, 0.023);
  EXPECT_DOUBLE_EQ(g.sigma_longitude_m, 0.020);
  EXPECT_DOUBLE_EQ(g.sigma_altitude_m, 0.031);
}

// Feeds a byte stream through framer and assembler; the fixes it completes.
std::vector<GnssFix> fixes_of(NmeaFixAssembler& a, const std::string& bytes) {
  NmeaFramer f;
  std::vector<GnssFix> out;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    NmeaFramer::Sentence s;
    GnssFix fix;
    if (f.push(static_cast<std::uint8_t>(bytes[i]), 1000 + static_cast<TimeNs>(i), &s) && a.add(s, &fix)) {
      out.push_back(fix);
    }
  }
  return out;
}

TEST(NmeaFixAssembler, AnEpochOfRmcGgaGsaAndGstIsOneFixWithTheReceiversSigmas) {
  NmeaFixConfig c;
  c.use_gst = true;
  NmeaFixAssembler a(c);
  const std::string t = "172814.00";
  const std::string epoch = sentence("GPRMC," + t + ",A,4807.038,N,01131.000,E,010.0,090.0,230394,,,D") +
                            sentence("GPGGA," + t + ",4807.038,N,01131.000,E,2,09,0.9,545.4,M,46.9,M,,") +
                            sentence("GPGSA,A,3,04,05,,09,12,,,24,,,,,2.5,1.3,2.1") +
                            sentence("GPGST," + t + ",0.006,0.023,0.020,273.6,0.023,0.020,0.031");
  const auto fixes = fixes_of(a, epoch);
  ASSERT_EQ(fixes.size(), 1u);
  const GnssFix& x = fixes[0];
  EXPECT_EQ(x.stamp, 1000);  // the first byte of the epoch's first sentence
  EXPECT_EQ(x.utc_ms_of_day, (17 * 3600 + 28 * 60 + 14) * 1000);
  EXPECT_EQ(x.status, GnssStatus::kSbasFix);
  EXPECT_EQ(x.solution, GnssSolution::kDifferential);
  EXPECT_EQ(x.covariance_type, GnssCovarianceType::kDiagonalKnown);
  EXPECT_DOUBLE_EQ(x.covariance_enu[0], 0.020 * 0.020);  // east: the longitude sigma
  EXPECT_DOUBLE_EQ(x.covariance_enu[4], 0.023 * 0.023);
  EXPECT_DOUBLE_EQ(x.covariance_enu[8], 0.031 * 0.031);
  ASSERT_TRUE(x.has_velocity);
  EXPECT_NEAR(x.velocity_enu[0], 10.0 * 1852.0 / 3600.0, 1e-9);  // due east
  EXPECT_NEAR(x.velocity_enu[1], 0.0, 1e-9);
  EXPECT_EQ(a.stats().other_sentences, 1);
  EXPECT_EQ(a.stats().incomplete_epochs, 0);
}

TEST(NmeaFixAssembler, WithoutGstTheCovarianceIsHdopTimesTheQualitysEpe) {
  NmeaFixConfig c;
  c.use_rmc = false;
  NmeaFixAssembler a(c);
  const auto fixes = fixes_of(a, std::string(kGga) +
                                     sentence("GPGGA,123520,4807.038,N,01131.000,E,4,12,0.8,545.4,M,46.9,M,1.0,0001"));
  ASSERT_EQ(fixes.size(), 2u);  // GGA alone completes an epoch
  EXPECT_EQ(fixes[0].status, GnssStatus::kFix);
  EXPECT_EQ(fixes[0].covariance_type, GnssCovarianceType::kApproximated);
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu[0], (0.9 * 4.0) * (0.9 * 4.0));
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu[8], 4.0 * (0.9 * 4.0) * (0.9 * 4.0));
  EXPECT_NEAR(fixes[0].altitude_m, 592.3, 1e-9);
  EXPECT_EQ(fixes[1].solution, GnssSolution::kRtkFixed);
  EXPECT_EQ(fixes[1].status, GnssStatus::kGbasFix);
  EXPECT_DOUBLE_EQ(fixes[1].covariance_enu[4], (0.8 * 0.02) * (0.8 * 0.02));
}

TEST(NmeaFixAssembler, AMissingGstClosesTheEpochIncompleteAtTheNext) {
  NmeaFixConfig c;
  c.use_rmc = false;
  c.use_gst = true;
  NmeaFixAssembler a(c);
  const auto fixes = fixes_of(a, std::string(kGga) +  // 12:35:19, its GST never comes
                                     sentence("GPGGA,123520,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,") +
                                     sentence("GPGST,123520,0.006,0.5,0.4,0.0,0.5,0.4,0.9"));
  ASSERT_EQ(fixes.size(), 2u);
  EXPECT_EQ(fixes[0].utc_ms_of_day, 45319000);
  EXPECT_EQ(fixes[0].covariance_type, GnssCovarianceType::kApproximated);
  EXPECT_EQ(fixes[1].covariance_type, GnssCovarianceType::kDiagonalKnown);
  EXPECT_EQ(a.stats().incomplete_epochs, 1);
  EXPECT_EQ(a.stats().fixes, 2);
}

TEST(NmeaFixAssembler, DeadReckoningAndAnInvalidRmcAreNoFix) {
  NmeaFixAssembler a(NmeaFixConfig{});
  const auto fixes = fixes_of(
      a, sentence("GPRMC,123519,A,4807.038,N,01131.000,E,001.0,090.0,230394,,,E") +
             sentence("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,") +
             sentence("GPRMC,123520,V,4807.038,N,01131.000,E,001.0,090.0,230394,,,A") +
             sentence("GPGGA,123520,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,") +
             sentence("GPRMC,123521,A,4807.038,N,01131.000,E,001.0,090.0,230394,,,A") +
             sentence("GPGGA,123521,4807.038,N,01131.000,E,6,00,,545.4,M,46.9,M,,"));
  ASSERT_EQ(fixes.size(), 3u);
  EXPECT_EQ(fixes[0].status, GnssStatus::kNoFix);
  EXPECT_TRUE(fixes[0].dead_reckoning);
  EXPECT_EQ(fixes[1].status, GnssStatus::kNoFix);  // RMC status V
  EXPECT_EQ(fixes[2].status, GnssStatus::kNoFix);  // GGA quality 6
  EXPECT_EQ(fixes[2].solution, GnssSolution::kDeadReckoning);
  EXPECT_EQ(fixes[2].covariance_type, GnssCovarianceType::kUnknown);  // no HDOP
}

TEST(NmeaFixAssembler, MalformedSentencesAreCountedAndNamed) {
  NmeaFixAssembler a(NmeaFixConfig{});
  fixes_of(a, sentence("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,abc,M,46.9,M,,"));
  EXPECT_EQ(a.stats().malformed, 1);
  EXPECT_STREQ(a.last_malformed(), "GGA altitude");
}

TEST(NmeaFixAssembler, NothingIsAllocatedPerByte) {
  NmeaFixConfig c;
  c.use_gst = true;
  NmeaFixAssembler a(c);
  NmeaFramer f;
  std::string stream;
  for (int i = 0; i < 20; ++i) {
    char t[16];
    std::snprintf(t, sizeof t, "1200%02d.00", i);
    stream += sentence(std::string("GPRMC,") + t + ",A,4807.038,N,01131.000,E,010.0,090.0,230394,,,A") +
              sentence(std::string("GPGGA,") + t + ",4807.038,N,01131.000,E,1,09,0.9,545.4,M,46.9,M,,") +
              sentence(std::string("GPGST,") + t + ",0.006,0.023,0.020,273.6,0.023,0.020,0.031");
  }
  int fixes = 0;
  test::AllocScope scope;
  for (char ch : stream) {
    NmeaFramer::Sentence s;
    GnssFix fix;
    if (f.push(static_cast<std::uint8_t>(ch), 0, &s) && a.add(s, &fix)) ++fixes;
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_EQ(fixes, 20);
}

}  // namespace gnss_nmea_test
}  // namespace rtfuse::drivers
