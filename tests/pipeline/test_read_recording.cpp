#include <gtest/gtest.h>
#include <fmt/format.h>

#include <cmath>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <random>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "diagnostic_queries.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/spindown_protocol.hpp"
#include "spindown/synthetic_run.hpp"

#include "lcm_log_events.hpp"

using namespace spindown;

using namespace spindown::testing;

namespace {

const std::string data_dir = SPINDOWN_SAMPLE_DATA;

struct TempFile {
  std::string path;
  TempFile(const std::string& name, const std::string& content)
      : path(::testing::TempDir() + "spindown_read_" + std::to_string(::getpid()) + "_" + name) {
    std::ofstream(path, std::ios::binary) << content;
  }
  ~TempFile() { std::filesystem::remove(path); }
};

using spindown::testing::write_event;

samples_t batch(const std::string& bench, std::int64_t seq, int n, std::int8_t quantity) {
  samples_t m{};
  m.bench = bench;
  m.seq = seq;
  m.quantity = quantity;
  m.n = n;
  for (int i = 0; i < n; ++i) {
    m.device_time_us.push_back((seq + i) * 20000);
    m.host_time_us.push_back(0);
    m.value.push_back(100.0 - i);
    m.raw_adc.push_back(-1);
  }
  return m;
}


}  // namespace

TEST(ReadRecording, SampleFilesAreArduinoText) {
  for (const auto& entry : std::filesystem::directory_iterator(data_dir)) {
    if (entry.path().extension() != ".tsv") continue;
    std::vector<RecordingInfo> info;
    const auto recs = read_recordings(entry.path().string(), {}, &info);
    ASSERT_EQ(recs.size(), 1u) << entry.path();
    ASSERT_EQ(info.size(), 1u);
    EXPECT_EQ(info[0].format, FileFormat::arduino_text) << entry.path();
    EXPECT_FALSE(recs[0].has_errors()) << all_diagnostics(recs[0]);
    EXPECT_GT(recs[0].size(), 1000u);
    EXPECT_EQ(recs[0].source, entry.path().string());
  }
}

TEST(ReadRecording, CsvIsDelimitedText) {
  TempFile f("run.csv", "time_s,rpm\n0.00,3000\n0.02,2990\n0.04,2980\n");
  std::vector<RecordingInfo> info;
  const auto recs = read_recordings(f.path, {}, &info);
  ASSERT_EQ(recs.size(), 1u);
  EXPECT_EQ(info[0].format, FileFormat::delimited_text);
  EXPECT_EQ(recs[0].quantity, Quantity::rpm);
  EXPECT_EQ(recs[0].size(), 3u) << all_diagnostics(recs[0]);
}

TEST(ReadRecording, NamingAColumnForcesDelimitedText) {
  TempFile f("lab.tsv", "1000\t2.00\n1020\t1.99\n1040\t1.98\n");
  ReadOptions o;
  o.delimited.time_unit = TimeUnit::ms;
  o.delimited.quantity = Quantity::rad_per_s;
  std::vector<RecordingInfo> info;
  const auto recs = read_recordings(f.path, o, &info);
  EXPECT_EQ(info.at(0).format, FileFormat::delimited_text);
  EXPECT_EQ(recs.at(0).quantity, Quantity::rad_per_s);
  EXPECT_DOUBLE_EQ(recs.at(0).t_s.at(1), 1.02);
}

TEST(ReadRecording, LcmLogGivesOneRecordingPerBench) {
  TempFile f("two.lcm", "");
  {
    lcm::LogFile log(f.path, "w");
    ASSERT_TRUE(log.good());
    config_t c{};
    c.bench = "b";
    c.inertia_kg_m2 = 2e-5;
    c.kb_v_s_per_rad = 0.01;
    write_event(log, "SPINDOWN.b.CONFIG", c, 1);
    write_event(log, "SPINDOWN.a.SAMPLE", batch("a", 0, 10, samples_t::QUANTITY_BACK_EMF_V), 2);
    write_event(log, "SPINDOWN.b.SAMPLE", batch("b", 0, 10, samples_t::QUANTITY_RPM), 3);
    write_event(log, "SPINDOWN.a.SAMPLE", batch("a", 15, 10, samples_t::QUANTITY_BACK_EMF_V), 4);
  }
  std::vector<RecordingInfo> info;
  const auto recs = read_recordings(f.path, {}, &info);
  ASSERT_EQ(recs.size(), 2u);
  ASSERT_EQ(info.size(), 2u);
  // Benches come in order of first appearance: b's config is the first event.
  EXPECT_EQ(info[0].format, FileFormat::lcm_log);
  EXPECT_EQ(info[0].bench, "b");
  ASSERT_TRUE(info[0].config);
  EXPECT_DOUBLE_EQ(info[0].config->inertia_kg_m2, 2e-5);
  EXPECT_EQ(recs[0].quantity, Quantity::rpm);
  EXPECT_EQ(recs[0].size(), 10u);
  EXPECT_EQ(info[1].bench, "a");
  EXPECT_EQ(info[1].samples_lost, 5);
  EXPECT_FALSE(info[1].config);
  EXPECT_EQ(recs[1].size(), 20u);
  EXPECT_NE(recs[1].source.find("SPINDOWN.a.SAMPLE"), std::string::npos);
}

TEST(ReadRecording, LcmLogWithoutSamplesIsAnError) {
  TempFile f("config-only.lcm", "");
  {
    lcm::LogFile log(f.path, "w");
    config_t c{};
    c.bench = "b";
    write_event(log, "SPINDOWN.b.CONFIG", c, 1);
    write_event(log, "SPINDOWN.b.STATUS", c, 2);
  }
  const auto recs = read_recordings(f.path);
  ASSERT_EQ(recs.size(), 1u);
  ASSERT_TRUE(recs[0].has_errors());
  EXPECT_TRUE(mentions(recs[0], "no samples: 2 events, none on SPINDOWN.<bench>.SAMPLE")) << all_diagnostics(recs[0]);
  EXPECT_TRUE(mentions(recs[0], "SPINDOWN.b.STATUS (1)"));
}

TEST(ReadRecording, DamageInALogIsCopiedToEveryBench) {
  TempFile f("damaged.lcm", "");
  {
    lcm::LogFile log(f.path, "w");
    write_event(log, "SPINDOWN.a.SAMPLE", batch("a", 0, 10, 0), 1);
    write_event(log, "SPINDOWN.b.SAMPLE", batch("b", 0, 10, 0), 2);
  }
  std::filesystem::resize_file(f.path, std::filesystem::file_size(f.path) - 7);
  const auto recs = read_recordings(f.path);
  ASSERT_EQ(recs.size(), 1u);  // bench b's only event is the truncated one
  EXPECT_TRUE(mentions(recs[0], "truncated")) << all_diagnostics(recs[0]);
  EXPECT_EQ(recs[0].size(), 10u);
}

TEST(ReadRecording, UnreadableInputsNameTheFileAndTheReason) {
  auto only_error = [](const std::vector<Recording>& recs) {
    EXPECT_EQ(recs.size(), 1u);
    EXPECT_TRUE(recs.at(0).has_errors());
    EXPECT_TRUE(recs.at(0).empty());
    return recs.at(0).diagnostics.back().message;
  };
  const std::string missing = only_error(read_recordings("/nonexistent/run.tsv"));
  EXPECT_NE(missing.find("/nonexistent/run.tsv"), std::string::npos);
  EXPECT_NE(missing.find("No such file or directory"), std::string::npos);

  EXPECT_NE(only_error(read_recordings(data_dir)).find("directory"), std::string::npos);

  TempFile empty("empty.tsv", "");
  EXPECT_EQ(only_error(read_recordings(empty.path)), "no samples: the file is empty");

  std::mt19937 rng(5);
  std::string junk(50'000, '\0');
  for (auto& c : junk) c = static_cast<char>(rng());
  TempFile bin("junk.bin", junk);
  EXPECT_NE(only_error(read_recordings(bin.path)).find("binary"), std::string::npos);

  TempFile zeros("zeros.bin", std::string(10'000, '\0'));
  EXPECT_NE(only_error(read_recordings(zeros.path)).find("no samples"), std::string::npos);

  if (::geteuid() != 0) {  // root reads anything
    TempFile locked("locked.tsv", "1\t2\n");
    std::filesystem::permissions(locked.path, std::filesystem::perms::none);
    EXPECT_NE(only_error(read_recordings(locked.path)).find("Permission denied"), std::string::npos);
  }
}

TEST(ReadRecording, SyntheticPuttyLogFromDisk) {
  SyntheticRunSpec spec;
  spec.lead_in = LeadIn::supply;
  const SyntheticRun run = make_synthetic_run(spec);
  TempFile f("synthetic.log", "=~=~=~ PuTTY log 2024.01.01 =~=~=~\r\n12\t3.00\r\n" + to_arduino_text(run));
  const auto recs = read_recordings(f.path);
  ASSERT_EQ(recs.size(), 1u);
  EXPECT_EQ(recs[0].size(), run.t_ms.size()) << all_diagnostics(recs[0]);
  EXPECT_TRUE(mentions(recs[0], "cut short"));
}

// Columns the other way round (volts<TAB>millis): refused with the options that read it, never
// fitted from the wrong column; following the proposal reads every sample. All readings negative
// (a differential probe's leads swapped): read as their magnitude, said.
TEST(ReadRecording, SwappedColumnsAreProposedAndNegativeReadingsSaid) {
  std::string swapped, negative;
  for (int i = 0; i < 300; ++i) {
    const double v = i < 50 ? 0.0 : 2.8 * std::exp(-(i - 50) * 0.01);
    swapped += fmt::format("{:.2f}\t{}\r\n", v, 1000 + 20 * i);
    negative += fmt::format("{}\t{:.2f}\r\n", 1000 + 20 * i, -v);
  }
  const TempFile s("swapped.txt", swapped);
  const auto rs = read_recordings(s.path);
  ASSERT_EQ(rs.size(), 1u);
  EXPECT_TRUE(rs[0].empty());
  std::string err;
  for (const auto& d : rs[0].diagnostics)
    if (d.severity == Diagnostic::Severity::error) err = d.message;
  EXPECT_NE(err.find("--time-column 2"), std::string::npos) << err;
  EXPECT_NE(err.find("--value-column 1"), std::string::npos) << err;
  ReadOptions o;
  o.delimited.time_column = "2";
  o.delimited.value_column = "1";
  o.delimited.time_unit = TimeUnit::ms;
  const auto followed = read_recordings(s.path, o);
  ASSERT_EQ(followed.size(), 1u);
  EXPECT_EQ(followed[0].size(), 300u);

  const TempFile n("negative.txt", negative);
  const auto rn = read_recordings(n.path);
  ASSERT_EQ(rn.size(), 1u);
  ASSERT_EQ(rn[0].size(), 300u);
  EXPECT_DOUBLE_EQ(rn[0].value[50], 2.8);
  bool said = false;
  for (const auto& d : rn[0].diagnostics) said = said || d.message.find("leads are the wrong way round") != std::string::npos;
  EXPECT_TRUE(said);
}

TEST(ReadRecording, DetectFormat) {
  const std::string magic("\xED\xA1\xDA\x01", 4);
  EXPECT_EQ(detect_format(magic + "rest"), FileFormat::lcm_log);
  EXPECT_EQ(detect_format("8245\t2.81\r\n8265\t2.80\r\n"), FileFormat::arduino_text);
  EXPECT_EQ(detect_format("=~=~=~ PuTTY log\r\n3\t0.00\r\n5234\t0.00\r\n"), FileFormat::arduino_text);
  EXPECT_EQ(detect_format("t,v\n0.0,1\n0.02,1\n"), FileFormat::delimited_text);
  EXPECT_EQ(detect_format("0.000 2.81\n0.020 2.80\n"), FileFormat::delimited_text);
  EXPECT_EQ(detect_format(""), FileFormat::arduino_text);
  ReadOptions o;
  o.format = FileFormat::delimited_text;
  EXPECT_EQ(detect_format("8245\t2.81\n", o), FileFormat::delimited_text);
  EXPECT_EQ(detect_format(magic, o), FileFormat::lcm_log);  // the magic word wins
  EXPECT_EQ(parse_file_format("csv"), FileFormat::delimited_text);
  EXPECT_EQ(parse_file_format("lcm"), FileFormat::lcm_log);
  EXPECT_FALSE(parse_file_format("xml"));
  EXPECT_EQ(file_format_name(FileFormat::arduino_text), "arduino");
}

TEST(ReadRecording, InvalidOptionsAreReported) {
  ReadOptions o;
  o.delimited.delimiter = '|';
  std::string why;
  EXPECT_FALSE(o.is_valid(&why));
  EXPECT_NE(why.find("delimited text"), std::string::npos);
  const auto recs = read_recordings(data_dir + "/seed-3v-run1.tsv", o);
  ASSERT_EQ(recs.size(), 1u);
  EXPECT_TRUE(recs[0].has_errors());
}

TEST(ReadRecording, ReadFileBytes) {
  TempFile f("bytes", std::string("a\0b", 3));
  std::string why;
  auto bytes = read_file_bytes(f.path, &why);
  ASSERT_TRUE(bytes);
  EXPECT_EQ(*bytes, std::string("a\0b", 3));
  EXPECT_FALSE(read_file_bytes(f.path, &why, 2));
  EXPECT_NE(why.find("more than"), std::string::npos);
  EXPECT_FALSE(read_file_bytes("/nonexistent", &why));
  EXPECT_NE(why.find("cannot open /nonexistent"), std::string::npos);
}

// Found by tests/integration/hostile_inputs.sh: `spindown fit` on a FIFO without a writer
// blocked forever in open(). It now reads as an empty file; a pipe with a writer is read to its
// end in one pass (it cannot be opened twice).
TEST(ReadRecordings, AFifoWithoutAWriterIsEmptyNotAHang) {
  const std::string fifo = ::testing::TempDir() + "spindown_read_fifo_" + std::to_string(::getpid());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto recs = read_recordings(fifo);
  std::filesystem::remove(fifo);
  ASSERT_EQ(recs.size(), 1u);
  EXPECT_TRUE(recs[0].empty());
  ASSERT_TRUE(recs[0].has_errors());
  EXPECT_NE(recs[0].diagnostics.back().message.find("empty"), std::string::npos)
      << recs[0].diagnostics.back().message;
}

TEST(ReadRecordings, APipeIsReadToItsEndAndDevNullIsEmpty) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  std::string text;
  for (int i = 0; i < 200; ++i) text += std::to_string(5000 + 20 * i) + "\t2.50\r\n";
  ASSERT_EQ(::write(fds[1], text.data(), text.size()), static_cast<ssize_t>(text.size()));
  ::close(fds[1]);
  const auto recs = read_recordings("/proc/self/fd/" + std::to_string(fds[0]));
  ::close(fds[0]);
  ASSERT_EQ(recs.size(), 1u);
  EXPECT_EQ(recs[0].size(), 200u);

  const auto null = read_recordings("/dev/null");
  ASSERT_EQ(null.size(), 1u);
  EXPECT_TRUE(null[0].empty());
  EXPECT_TRUE(null[0].has_errors());
}

// A log up to 1 MiB is read whole before its first word is looked at, a larger one has that word
// read alone: both are recognised and streamed, with every sample.
TEST(ReadRecordings, LcmLogsBelowAndAboveTheWholeReadSizeGiveEverySample) {
  for (const int batches : {10, 4000}) {  // ~2 kB and ~4 MB of SAMPLE messages, 50 samples each
    TempFile f("size" + std::to_string(batches) + ".lcm", "");
    {
      lcm::LogFile log(f.path, "w");
      ASSERT_TRUE(log.good());
      for (int k = 0; k < batches; ++k)
        write_event(log, "SPINDOWN.a.SAMPLE", batch("a", 50 * k, 50, samples_t::QUANTITY_BACK_EMF_V), k + 1);
    }
    const auto size = std::filesystem::file_size(f.path);
    EXPECT_EQ(size > (1u << 20), batches == 4000) << size << " bytes";
    std::vector<RecordingInfo> info;
    const auto recs = read_recordings(f.path, {}, &info);
    ASSERT_EQ(recs.size(), 1u) << all_diagnostics(recs[0]);
    EXPECT_EQ(info[0].format, FileFormat::lcm_log);
    EXPECT_EQ(recs[0].size(), 50u * static_cast<std::size_t>(batches));
  }
}

// lcm::LogFile seeks, so an LCM log through a pipe is refused, by name, not read as text.
TEST(ReadRecordings, AnLcmLogThroughAPipeIsRefusedByName) {
  TempFile f("piped.lcm", "");
  {
    lcm::LogFile log(f.path, "w");
    ASSERT_TRUE(log.good());
    write_event(log, "SPINDOWN.a.SAMPLE", batch("a", 0, 10, samples_t::QUANTITY_BACK_EMF_V), 1);
  }
  std::ifstream in(f.path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_LT(bytes.size(), 4096u);  // fits the pipe's buffer: no writer thread needed
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  ASSERT_EQ(::write(fds[1], bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  ::close(fds[1]);
  const auto recs = read_recordings("/proc/self/fd/" + std::to_string(fds[0]));
  ::close(fds[0]);
  ASSERT_EQ(recs.size(), 1u);
  EXPECT_TRUE(recs[0].has_errors());
  EXPECT_TRUE(mentions(recs[0], "it is a pipe or device")) << all_diagnostics(recs[0]);
}

namespace {

SpindownBanner coast_banner() {
  SpindownBanner b;
  b.firmware = "spindown-coast";
  b.version = "1.0.0";
  b.period_us = 5000;
  b.baud = 115200;
  return b;
}

// n samples from seq 0, every 5 ms from 1.6 s after boot, falling counts.
std::string v1_samples(int n, int skip_from = -1, int skip = 0) {
  std::string s;
  for (int i = 0; i < n; ++i)
    if (i < skip_from || i >= skip_from + skip)
      s += format_spindown_sample(std::uint32_t(i), std::uint32_t(1'600'000 + 5000 * i), 900 - i / 3);
  return s;
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

TEST(ReadRecording, ASpindownV1CaptureIsReadAsOne) {
  // Saved by PuTTY from the port of a board running spindown_coast: 3 lines lost on the wire.
  const std::string text = "=~=~=~=~=~=~=~=~=~=~=~= PuTTY log 2024.03.05 14:02:11 =~=~=~=~=~=~=~=~=~=~=~=\r\n" +
                           format_spindown_banner(coast_banner()) + v1_samples(400, 200, 3);
  TempFile f("coast.log", text);
  std::vector<RecordingInfo> info;
  const auto recs = read_recordings(f.path, {}, &info);
  ASSERT_EQ(recs.size(), 1u);
  ASSERT_EQ(info.size(), 1u);
  EXPECT_EQ(info[0].format, FileFormat::spindown_v1);
  EXPECT_EQ(info[0].samples_lost, 3);
  const Recording& r = recs[0];
  EXPECT_FALSE(r.has_errors()) << all_diagnostics(r);
  EXPECT_EQ(r.source, f.path);
  EXPECT_EQ(r.quantity, Quantity::back_emf_volts);
  ASSERT_EQ(r.size(), 397u);
  EXPECT_EQ(r.t_s[0], 1.6);
  EXPECT_EQ(r.value[0], coast_banner().volts(900));
  EXPECT_TRUE(mentions(r, "3 samples lost"));
  EXPECT_TRUE(mentions(r, "banner: spindown-coast 1.0.0"));
  // The same bytes named as Arduino text are not read as samples: the format was the reader's choice.
  ReadOptions o;
  o.format = FileFormat::arduino_text;
  const auto as_lab = read_recordings(f.path, o);
  ASSERT_EQ(as_lab.size(), 1u);
  EXPECT_TRUE(as_lab[0].has_errors());
}

TEST(ReadRecording, DetectSpindownV1) {
  const std::string banner = format_spindown_banner(coast_banner());
  const std::string putty = "=~=~=~ PuTTY log 2024.03.05 14:02:11 =~=~=~\r\n";
  EXPECT_EQ(detect_format(banner + v1_samples(60)), FileFormat::spindown_v1);
  EXPECT_EQ(detect_format(putty + banner + v1_samples(60)), FileFormat::spindown_v1);
  EXPECT_EQ(detect_format(v1_samples(60)), FileFormat::spindown_v1);  // capture began after the banner
  EXPECT_EQ(detect_format(putty + "000,612*3A\r\n" + v1_samples(5)), FileFormat::spindown_v1);  // cut first line
  EXPECT_EQ(detect_format(banner + "garbage\r\nmore garbage\r\n"), FileFormat::spindown_v1);  // the banner says it
  // Half or more of the content lines must be valid samples; bad checksums do not count.
  std::string noisy = v1_samples(10);
  for (int i = 0; i < 11; ++i) noisy += "S,1,2,3*00\r\n";
  EXPECT_NE(detect_format(noisy), FileFormat::spindown_v1);
  // Lab text with '#' comments and a lone v1-looking line stays Arduino text.
  EXPECT_EQ(detect_format("# motor 3\r\n8245\t2.81\r\n8265\t2.80\r\n8285\t2.79\r\n" + v1_samples(1)),
            FileFormat::arduino_text);
  ReadOptions o;
  o.format = FileFormat::delimited_text;
  EXPECT_EQ(detect_format(banner + v1_samples(5), o), FileFormat::delimited_text);  // a named format wins
  o.format = FileFormat::spindown_v1;
  EXPECT_EQ(detect_format("8245\t2.81\r\n", o), FileFormat::spindown_v1);
  EXPECT_EQ(parse_file_format("spindown-v1"), FileFormat::spindown_v1);
  EXPECT_EQ(parse_file_format("v1"), FileFormat::spindown_v1);
  EXPECT_EQ(file_format_name(FileFormat::spindown_v1), "spindown-v1");
  // The fuzz seeds of the protocol that are captures (a stream, the banner, a sample, avr_bench.sh's port).
  const std::string corpus = std::string(SPINDOWN_SOURCE_DIR) + "/fuzz/corpus/fuzz_spindown_protocol/";
  for (const char* name : {"stream", "banner", "sample", "putty_capture"})
    EXPECT_EQ(detect_format(file_bytes(corpus + name)), FileFormat::spindown_v1) << name;
}

// The lab's files, the fuzz corpora of the other readers and the hostile inputs' kinds are detected
// as they were before spindown-v1 was: no lab or delimited file passes for a capture.
TEST(ReadRecording, OtherReadersCorporaKeepTheirFormats) {
  const std::string fuzz = std::string(SPINDOWN_SOURCE_DIR) + "/fuzz/corpus/";
  const std::vector<std::pair<std::string, FileFormat>> want = {
      {"fuzz_arduino_text/crash-putty-header-not-utf8", FileFormat::arduino_text},
      {"fuzz_arduino_text/cut.tsv", FileFormat::arduino_text},
      {"fuzz_arduino_text/hostile.tsv", FileFormat::arduino_text},
      {"fuzz_arduino_text/millis_wrap.tsv", FileFormat::arduino_text},
      {"fuzz_arduino_text/putty_head.tsv", FileFormat::arduino_text},
      {"fuzz_arduino_text/reset.tsv", FileFormat::arduino_text},
      {"fuzz_arduino_text/two_sessions.tsv", FileFormat::arduino_text},
      {"fuzz_delimited_text/blanks_rpm", FileFormat::delimited_text},
      {"fuzz_delimited_text/crash-field-not-utf8", FileFormat::arduino_text},
      {"fuzz_delimited_text/csv_header", FileFormat::delimited_text},
      {"fuzz_delimited_text/ragged", FileFormat::delimited_text},
      {"fuzz_delimited_text/real_lines", FileFormat::arduino_text},
      {"fuzz_delimited_text/semicolon_decimal_comma", FileFormat::delimited_text},
      {"fuzz_delimited_text/tsv_ms", FileFormat::arduino_text},
      {"fuzz_spindown_protocol/lab_line", FileFormat::arduino_text},
      {"fuzz_spindown_protocol/bad_crc", FileFormat::delimited_text},
      {"fuzz_spindown_protocol/note", FileFormat::delimited_text},
      {"fuzz_lcm_log/damaged.lcmlog", FileFormat::lcm_log},
  };
  for (const auto& [name, format] : want)
    EXPECT_EQ(detect_format(file_bytes(fuzz + name)), format) << name;
  for (const auto& entry : std::filesystem::directory_iterator(data_dir)) {
    if (entry.path().extension() == ".tsv") {
      EXPECT_EQ(detect_format(file_bytes(entry.path().string())), FileFormat::arduino_text) << entry.path();
    }
  }
}
