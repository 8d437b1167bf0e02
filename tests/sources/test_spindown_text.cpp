#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "diagnostic_queries.hpp"
#include "spindown/spindown_protocol.hpp"
#include "spindown/spindown_text.hpp"
#include "spindown/synthetic_run.hpp"

using namespace spindown;
using Severity = Diagnostic::Severity;

using namespace spindown::testing;

namespace {


bool strictly_increasing(const std::vector<double>& t, std::size_t from = 0, std::size_t to = SIZE_MAX) {
  to = std::min(to, t.size());
  for (std::size_t i = from + 1; i < to; ++i)
    if (t[i] <= t[i - 1]) return false;
  return true;
}

SpindownBanner coast_banner(double ref_v = 5.0, int bits = 10, std::uint32_t period_us = 5000) {
  SpindownBanner b;
  b.firmware = "spindown-coast";
  b.version = "1.0.0";
  b.adc_bits = bits;
  b.adc_ref_v = ref_v;
  b.period_us = period_us;
  b.baud = 115200;
  return b;
}

struct Sample {
  std::uint32_t seq, time_us;
  int adc;
};

// `count` samples every period_us from (seq, time_us), the count falling as a coast does.
std::vector<Sample> cadence(std::uint32_t seq, std::uint32_t time_us, int count, std::uint32_t period_us = 5000,
                            int adc = 600) {
  std::vector<Sample> out;
  for (int i = 0; i < count; ++i)
    out.push_back({seq + std::uint32_t(i), time_us + std::uint32_t(i) * period_us, std::max(0, adc - i / 4)});
  return out;
}

std::string print(const std::vector<Sample>& samples) {
  std::string s;
  for (const Sample& x : samples) s += format_spindown_sample(x.seq, x.time_us, x.adc);
  return s;
}

}  // namespace

TEST(SpindownText, CaptureOfACoastRoundTripsExactly) {
  // The firmware's bytes for a synthetic coast: banner, then every sample as it prints them.
  SyntheticRunSpec spec;
  spec.period_s = 0.005;
  spec.jitter_s = 0;
  spec.adc_ref_v = 4.096;  // not the default: the banner's conversion must be the one used
  spec.decimals = -1;
  const SyntheticRun run = make_synthetic_run(spec);
  const SpindownBanner banner = coast_banner(4.096);
  std::string text = format_spindown_banner(banner);
  std::vector<std::uint32_t> micros;
  for (std::size_t i = 0; i < run.t_ms.size(); ++i) {
    micros.push_back(static_cast<std::uint32_t>(std::llround(run.t_ms[i] * 1000)));
    text += format_spindown_sample(static_cast<std::uint32_t>(i), micros.back(), run.adc[i]);
  }
  ASSERT_GT(run.t_ms.size(), 1000u);

  std::int64_t lost = -1;
  const Recording r = read_spindown_text(text, "coast.log", {}, &lost);
  SCOPED_TRACE(all_diagnostics(r));
  EXPECT_FALSE(r.has_errors());
  EXPECT_TRUE(with(r, Severity::warning).empty());
  EXPECT_EQ(r.quantity, Quantity::back_emf_volts);
  EXPECT_EQ(r.source, "coast.log");
  ASSERT_EQ(r.size(), run.t_ms.size());
  for (std::size_t i = 0; i < r.size(); ++i) {
    ASSERT_EQ(r.t_s[i], static_cast<double>(micros[i]) / 1e6) << i;  // as the fitter converts device_time_us
    ASSERT_EQ(r.value[i], banner.volts(run.adc[i])) << i;            // as the bridge converts
  }
  EXPECT_NEAR(r.value[0], banner.adc_ref_v * run.adc[0] / 1024.0, 1e-12);
  EXPECT_TRUE(r.clock_restarts.empty());
  EXPECT_EQ(lost, 0);
  EXPECT_EQ(r.lines_read, run.t_ms.size() + 1);
  EXPECT_EQ(r.lines_read, r.size() + r.lines_skipped);
  // The banner's facts as a note on its line.
  ASSERT_NE(at_line(r, 1), nullptr);
  EXPECT_EQ(at_line(r, 1)->severity, Severity::note);
  EXPECT_NE(at_line(r, 1)->message.find("spindown-coast 1.0.0, 10-bit ADC at 4.096 V full scale"), std::string::npos)
      << at_line(r, 1)->message;
}

TEST(SpindownText, MicrosWrapIsUnwrapped) {
  // micros() passes 2^32 (after 71.6 min) in the middle of the capture.
  const std::uint32_t start = 4294967296ull - 50 * 5000 + 1234;
  const auto samples = cadence(1000, start, 200);
  const Recording r = read_spindown_text(format_spindown_banner(coast_banner()) + print(samples), "wrap.log");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 200u);
  EXPECT_TRUE(with(r, Severity::warning).empty());
  EXPECT_TRUE(r.clock_restarts.empty());
  EXPECT_TRUE(strictly_increasing(r.t_s));
  EXPECT_EQ(r.t_s[0], start / 1e6);
  EXPECT_EQ(r.t_s[199], (4294967296.0 + samples[199].time_us) / 1e6);
  EXPECT_NEAR(r.t_s[199] - r.t_s[0], 199 * 0.005, 1e-9);
  // The sample after the wrap is line 2 + 50 (the banner is line 1).
  ASSERT_NE(at_line(r, 52), nullptr);
  EXPECT_NE(at_line(r, 52)->message.find("wrapped"), std::string::npos);
  EXPECT_TRUE(mentions(r, "1 clock wrap"));
}

TEST(SpindownText, AResetMidFileStartsANewTimeline) {
  // Booted, 300 samples, reset (the banner again, seq from 0, micros from boot): two timelines.
  const std::string banner = format_spindown_banner(coast_banner());
  const std::string text = banner + print(cadence(0, 1'600'000, 300)) + banner + print(cadence(0, 1'600'120, 200));
  const Recording r = read_spindown_text(text, "reset.log");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 500u);
  ASSERT_EQ(r.clock_restarts, std::vector<std::size_t>{300});
  EXPECT_TRUE(strictly_increasing(r.t_s, 0, 300));
  EXPECT_TRUE(strictly_increasing(r.t_s, 300));
  EXPECT_EQ(r.t_s[300], 1.600120);  // the new clock, not continued from the old one
  EXPECT_TRUE(with(r, Severity::warning).empty());  // no sequence gap across the reset
  const Diagnostic* d = at_line(r, 1 + 300 + 2);    // the first sample after the second banner
  ASSERT_NE(d, nullptr);
  EXPECT_NE(d->message.find("board reset"), std::string::npos) << d->message;
  EXPECT_TRUE(mentions(r, "1 clock restart"));
}

TEST(SpindownText, AResetSeenOnlyByTheSequenceAfterABanner) {
  // A reset so soon after the last one that micros() is ahead of the previous sample: the banner
  // and the sequence starting again still say the board restarted.
  const std::string banner = format_spindown_banner(coast_banner());
  const std::string text = banner + print(cadence(0, 1'600'000, 20)) + banner + print(cadence(0, 1'800'000, 100));
  const Recording r = read_spindown_text(text, "quick-reset.log");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 120u);
  EXPECT_EQ(r.clock_restarts, std::vector<std::size_t>{20});
  EXPECT_TRUE(mentions(r, "board reset: a banner, then the sequence starts again at 0"));
}

TEST(SpindownText, ABannerOnRequestIsNoReset) {
  // "?" or "P5" make the firmware print its banner while its clock and sequence run on.
  const std::string banner = format_spindown_banner(coast_banner());
  const std::string text = banner + print(cadence(0, 1'600'000, 100)) + banner + print(cadence(100, 2'100'000, 100));
  const Recording r = read_spindown_text(text, "query.log");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 200u);
  EXPECT_TRUE(r.clock_restarts.empty());
  EXPECT_TRUE(strictly_increasing(r.t_s));
  EXPECT_TRUE(with(r, Severity::warning).empty());
}

TEST(SpindownText, TimeGoingBackWithoutABannerIsAReset) {
  // The banner was lost (garbled): micros() going back says the board restarted.
  const std::string text = format_spindown_banner(coast_banner()) + print(cadence(0, 9'000'000, 100)) +
                           "#spindown-v1 firmware=spindown-coast garbled*00\r\n" + print(cadence(0, 1'600'000, 100));
  const Recording r = read_spindown_text(text, "reset2.log");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 200u);
  EXPECT_EQ(r.clock_restarts, std::vector<std::size_t>{100});
  EXPECT_TRUE(mentions(r, "micros() goes back from 9495000 µs (line 101) to 1600000 µs"));
  EXPECT_EQ(with(r, Severity::warning).size(), 1u);  // the garbled banner
}

TEST(SpindownText, ACrcErrorSkipsTheLineAndCountsItsSampleLost) {
  const auto samples = cadence(0, 1'000'000, 100);
  std::string text = format_spindown_banner(coast_banner());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    std::string line = format_spindown_sample(samples[i].seq, samples[i].time_us, samples[i].adc);
    if (i == 40) line[line.find(',', 2) + 1] ^= 0x02;  // one bit flipped on the wire in micros
    text += line;
  }
  std::int64_t lost = 0;
  const Recording r = read_spindown_text(text, "crc.log", {}, &lost);
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 99u);
  EXPECT_EQ(lost, 1);
  const Diagnostic* bad = at_line(r, 42);  // banner on line 1, sample 40 on line 42
  ASSERT_NE(bad, nullptr);
  EXPECT_EQ(bad->severity, Severity::warning);
  EXPECT_NE(bad->message.find("checksum mismatch; skipped"), std::string::npos) << bad->message;
  EXPECT_NE(bad->to_string().find("crc.log:42: warning:"), std::string::npos);
  const Diagnostic* gap = at_line(r, 43);
  ASSERT_NE(gap, nullptr);
  EXPECT_NE(gap->message.find("jumps from 39 (line 41) to 41 (line 43): 1 sample lost (line 42 between was garbled)"),
            std::string::npos)
      << gap->message;
  EXPECT_EQ(r.lines_read, r.size() + r.lines_skipped);
}

TEST(SpindownText, ASequenceGapIsReportedAsLostSamples) {
  auto samples = cadence(0, 1'000'000, 200);
  samples.erase(samples.begin() + 120, samples.begin() + 127);  // 7 lines never arrived
  std::int64_t lost = 0;
  const Recording r = read_spindown_text(format_spindown_banner(coast_banner()) + print(samples), "gap.log", {}, &lost);
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 193u);
  EXPECT_EQ(lost, 7);
  const auto warnings = with(r, Severity::warning);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0]->line, 122);
  EXPECT_NE(warnings[0]->message.find("jumps from 119 (line 121) to 127 (line 122): 7 samples lost"),
            std::string::npos)
      << warnings[0]->message;
  EXPECT_TRUE(mentions(r, "7 lost in sequence gaps"));
  EXPECT_TRUE(strictly_increasing(r.t_s));
  EXPECT_TRUE(r.clock_restarts.empty());
}

TEST(SpindownText, GarbageLinesAreNamedAndTheRestIsUsed) {
  const auto samples = cadence(0, 1'000'000, 100);
  std::string text = format_spindown_banner(coast_banner());
  const std::vector<std::string> junk = {"\x7f\x01garbage\xff\r\n", "S,12,abc,5*00\r\n", "5234\t3.00\r\n",
                                         "S,41,5254000,611\r\n", "#note without checksum\r\n"};
  std::vector<std::int64_t> junk_lines;
  std::int64_t line = 1;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (i % 20 == 10) {
      text += junk[junk_lines.size()];
      junk_lines.push_back(++line);
    }
    text += format_spindown_sample(samples[i].seq, samples[i].time_us, samples[i].adc);
    ++line;
  }
  ASSERT_EQ(junk_lines.size(), junk.size());
  const Recording r = read_spindown_text(text, "junk.log");
  SCOPED_TRACE(all_diagnostics(r));
  EXPECT_FALSE(r.has_errors());
  ASSERT_EQ(r.size(), 100u);
  const auto warnings = with(r, Severity::warning);
  ASSERT_EQ(warnings.size(), junk.size());
  for (std::size_t k = 0; k < junk.size(); ++k) {
    EXPECT_EQ(warnings[k]->line, junk_lines[k]);
    EXPECT_NE(warnings[k]->message.find("; skipped"), std::string::npos) << warnings[k]->message;
  }
  EXPECT_NE(warnings[0]->message.find("\\x7f\\x01garbage\\xff"), std::string::npos);  // quoted, escaped
  EXPECT_NE(warnings[2]->message.find("not a spindown-v1 line"), std::string::npos);
  EXPECT_NE(warnings[3]->message.find("no '*' checksum"), std::string::npos);
  EXPECT_EQ(r.lines_read, 1 + samples.size() + junk.size());
  EXPECT_EQ(r.lines_skipped, 1 + junk.size());
}

TEST(SpindownText, TooManyBadLinesAreCounted) {
  std::string text = format_spindown_banner(coast_banner());
  for (int i = 0; i < 100; ++i) text += format_spindown_sample(i, 1'000'000 + 5000 * i, 500) + "S,garbled*00\r\n";
  SpindownTextOptions o;
  o.max_line_reports = 5;
  const Recording r = read_spindown_text(text, "flood.log", o);
  SCOPED_TRACE(all_diagnostics(r));
  EXPECT_EQ(r.size(), 100u);
  EXPECT_EQ(with(r, Severity::warning).size(), 6u);  // 5 listed, then the count
  EXPECT_TRUE(mentions(r, "95 more problem lines not listed one by one"));
}

TEST(SpindownText, APuttyLogCutInItsFirstAndLastLine) {
  // PuTTY started logging mid-line (the end of a sample) and the file ends mid-line.
  const auto samples = cadence(57, 2'000'000, 100);
  const std::string first = format_spindown_sample(56, 1'995'000, 610);
  const std::string text = std::string(putty_log_header) + first.substr(5) + print(samples) + "S,157,2500";
  const Recording r = read_spindown_text(text, "putty.log");
  SCOPED_TRACE(all_diagnostics(r));
  EXPECT_FALSE(r.has_errors());
  ASSERT_EQ(r.size(), 100u);
  EXPECT_TRUE(with(r, Severity::warning).size() == 1u);  // before any banner (it was not captured)
  ASSERT_NE(at_line(r, 1), nullptr);
  EXPECT_NE(at_line(r, 1)->message.find("PuTTY log header skipped (log started 2023.09.14 10:21:33)"),
            std::string::npos);
  ASSERT_NE(at_line(r, 2), nullptr);
  EXPECT_EQ(at_line(r, 2)->severity, Severity::note);
  EXPECT_NE(at_line(r, 2)->message.find("probably cut short when logging started mid-line"), std::string::npos);
  const Diagnostic* last = at_line(r, 103);
  ASSERT_NE(last, nullptr);
  EXPECT_EQ(last->severity, Severity::note);
  EXPECT_NE(last->message.find("the file ends mid-line"), std::string::npos) << last->message;
  EXPECT_EQ(r.t_s[0], 2.0);
  EXPECT_EQ(r.lines_read, 103u);
  EXPECT_TRUE(mentions(r, "100 spindown-v1 samples from 103 lines, 1 PuTTY header, 2 cut short, 100 before any banner"));
}

TEST(SpindownText, SamplesBeforeAnyBannerUseTheDefaultsWithAWarning) {
  // The capture began after the banner; the board's banner (later, on "?") says 4.096 V.
  const std::string text = print(cadence(300, 3'000'000, 50, 5000, 1000)) + format_spindown_banner(coast_banner(4.096)) +
                           print(cadence(350, 3'250'000, 50, 5000, 1000));
  const Recording r = read_spindown_text(text, "late.log");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 100u);
  const auto warnings = with(r, Severity::warning);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0]->line, 1);
  EXPECT_NE(warnings[0]->message.find("50 samples from this line on came before any banner: converted with the "
                                      "protocol's defaults (10-bit ADC at 5.000 V full scale)"),
            std::string::npos)
      << warnings[0]->message;
  EXPECT_EQ(r.value[0], SpindownBanner{}.volts(1000));
  EXPECT_DOUBLE_EQ(r.value[0], 1000 * 5.0 / 1024);
  EXPECT_EQ(r.value[50], coast_banner(4.096).volts(1000));
  EXPECT_TRUE(r.clock_restarts.empty());
}

TEST(SpindownText, ACountAboveTheBannersConverterIsRefused) {
  const std::string text = format_spindown_banner(coast_banner(5.0, 8)) + print(cadence(0, 1'000'000, 20, 5000, 200)) +
                           format_spindown_sample(20, 1'100'000, 300) + print(cadence(21, 1'105'000, 20, 5000, 200));
  const Recording r = read_spindown_text(text, "range.log");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 40u);
  const Diagnostic* d = at_line(r, 22);
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->severity, Severity::warning);
  EXPECT_NE(d->message.find("ADC count 300 above the 8-bit converter's range (0-255)"), std::string::npos);
}

TEST(SpindownText, FirmwareNotesAndDuplicatesAreReported) {
  const auto samples = cadence(0, 1'000'000, 60);
  const std::string text = format_spindown_banner(coast_banner()) + print({samples.begin(), samples.begin() + 30}) +
                           format_spindown_note("error period must be 1-20 ms") +
                           print({samples.begin() + 29, samples.end()});  // line 31 printed twice
  const Recording r = read_spindown_text(text, "notes.log");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 60u);
  ASSERT_NE(at_line(r, 32), nullptr);
  EXPECT_EQ(at_line(r, 32)->severity, Severity::note);
  EXPECT_NE(at_line(r, 32)->message.find("firmware note \"error period must be 1-20 ms\""), std::string::npos);
  ASSERT_NE(at_line(r, 33), nullptr);
  EXPECT_EQ(at_line(r, 33)->severity, Severity::warning);
  EXPECT_NE(at_line(r, 33)->message.find("repeats line 31"), std::string::npos) << at_line(r, 33)->message;
  EXPECT_TRUE(strictly_increasing(r.t_s));
}

TEST(SpindownText, NothingUsableIsAnErrorSayingWhy) {
  {
    const Recording r = read_spindown_text("", "empty.log");
    EXPECT_TRUE(r.has_errors());
    EXPECT_TRUE(mentions(r, "no samples: the file is empty"));
  }
  {
    const Recording r = read_spindown_text(std::string(4096, '\0'), "zeros.bin");
    EXPECT_TRUE(mentions(r, "no samples: binary data, not spindown-v1 text"));
  }
  {
    const Recording r = read_spindown_text(format_spindown_banner(coast_banner()) + "S,1,2*00\r\nhello\r\n", "bad.log");
    EXPECT_TRUE(r.empty());
    EXPECT_TRUE(r.has_errors());
    EXPECT_TRUE(mentions(r, "no samples: none of the 3 lines is a spindown-v1 sample (line 2: checksum mismatch)"))
        << all_diagnostics(r);
  }
  {
    const Recording r = read_spindown_text(format_spindown_banner(coast_banner()) + "\r\n", "banner-only.log");
    EXPECT_TRUE(mentions(r, "no samples: 2 lines, 1 blank, 0 header lines, 1 banners")) << all_diagnostics(r);
  }
  SpindownTextOptions o;
  o.max_line_reports = 0;
  std::string why;
  EXPECT_FALSE(o.is_valid(&why));
  EXPECT_TRUE(mentions(read_spindown_text("S,0,0,0*00", "x", o), "invalid reader options"));
}

TEST(SpindownText, ReadsAFileAndNamesAMissingOne) {
  const Recording r = read_spindown_text_file("/nonexistent/capture.log");
  EXPECT_TRUE(r.has_errors());
  EXPECT_EQ(r.source, "/nonexistent/capture.log");
  EXPECT_TRUE(mentions(r, "/nonexistent/capture.log"));
}
