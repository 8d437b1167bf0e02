// The lab key: read from a file as 32 raw bytes or 64 hex digits, refused otherwise with the
// file named; `spindown keygen` never overwrites; the units' systemd credential is found.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

#include "spindown/lab_key.hpp"
#include "spindown/lab_settings.hpp"

namespace spindown {
namespace {

namespace fs = std::filesystem;

struct TempDir {
  fs::path path;
  TempDir() {
    char tmpl[] = "/tmp/spindown-lab-key.XXXXXX";
    path = ::mkdtemp(tmpl);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string write(const std::string& name, const std::string& bytes, mode_t mode = 0600) {
    const auto p = path / name;
    std::ofstream(p, std::ios::binary) << bytes;
    ::chmod(p.c_str(), mode);
    return p.string();
  }
};

TEST(LabKey, RawAndHexFilesGiveTheSameKey) {
  TempDir d;
  std::string raw(32, '\0');
  std::string hex;
  for (int i = 0; i < 32; ++i) {
    raw[static_cast<std::size_t>(i)] = static_cast<char>(i * 7 + 1);
    hex += "0123456789abcdef"[((i * 7 + 1) >> 4) & 15];
    hex += "0123456789abcdef"[(i * 7 + 1) & 15];
  }
  std::string why;
  const auto a = load_lab_key(d.write("raw.key", raw), &why);
  ASSERT_TRUE(a) << why;
  const auto b = load_lab_key(d.write("hex.key", hex + "\n"), &why);
  ASSERT_TRUE(b) << why;
  EXPECT_EQ(a->bytes, b->bytes);
  EXPECT_EQ(a->id, b->id);
  EXPECT_NE(a->id, 0);
  EXPECT_TRUE(a->warning.empty());
  const auto open = load_lab_key(d.write("open.key", raw, 0644), &why);
  ASSERT_TRUE(open);
  EXPECT_NE(open->warning.find("readable by every user"), std::string::npos) << open->warning;
}

TEST(LabKey, AnythingElseIsRefusedNamingTheFile) {
  TempDir d;
  std::string why;
  EXPECT_FALSE(load_lab_key(d.write("short.key", "too short"), &why));
  EXPECT_NE(why.find("short.key: 9 bytes; a key is 32 bytes"), std::string::npos) << why;
  EXPECT_FALSE(load_lab_key(d.write("long.key", std::string(1000, 'x')), &why));
  EXPECT_NE(why.find("more than 160"), std::string::npos) << why;
  EXPECT_FALSE(load_lab_key(d.write("nothex.key", std::string(64, 'g')), &why));
  EXPECT_FALSE(load_lab_key((d.path / "missing.key").string(), &why));
  EXPECT_NE(why.find("missing.key: No such file"), std::string::npos) << why;
  EXPECT_FALSE(load_lab_key(d.path.string(), &why));
  EXPECT_NE(why.find("not a regular file"), std::string::npos) << why;
}

TEST(LabKey, KeygenMakesAPrivateKeyAndNeverOverwrites) {
  TempDir d;
  const std::string p = (d.path / "lab.key").string();
  std::string why;
  ASSERT_TRUE(write_new_lab_key(p, &why)) << why;
  struct stat st {};
  ASSERT_EQ(::stat(p.c_str(), &st), 0);
  EXPECT_EQ(st.st_size, 32);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  const auto first = load_lab_key(p, &why);
  ASSERT_TRUE(first) << why;
  EXPECT_FALSE(write_new_lab_key(p, &why));
  EXPECT_NE(why.find("never overwritten"), std::string::npos) << why;
  EXPECT_EQ(load_lab_key(p)->bytes, first->bytes);
  const std::string q = (d.path / "other.key").string();
  ASSERT_TRUE(write_new_lab_key(q));
  EXPECT_NE(load_lab_key(q)->bytes, first->bytes);
}

TEST(LabKey, TheOptionElseTheSystemdCredentialElseNone) {
  TempDir d;
  const std::string key = d.write("mine.key", std::string(32, 'k'));
  EXPECT_FALSE(choose_lab_key("", std::nullopt).key);
  EXPECT_FALSE(choose_lab_key("", d.path.string()).key);  // a credentials dir without lab-key
  d.write(lab_key_credential, std::string(32, 'c'));
  const LabKeyChoice cred = choose_lab_key("", d.path.string());
  ASSERT_TRUE(cred.key) << cred.error;
  EXPECT_EQ(cred.source, "systemd credential lab-key");
  const LabKeyChoice opt = choose_lab_key(key, d.path.string());
  ASSERT_TRUE(opt.key);
  EXPECT_EQ(opt.source, "--key " + key);
  EXPECT_NE(opt.key->id, cred.key->id);
  const LabKeyChoice bad = choose_lab_key((d.path / "nope").string(), std::nullopt);
  EXPECT_FALSE(bad.key);
  EXPECT_NE(bad.error.find("nope"), std::string::npos);
  std::string why;
  EXPECT_FALSE(resolve_lab_settings("bad name!", "", &why));
  EXPECT_NE(why.find("--lab 'bad name!'"), std::string::npos) << why;
  const auto s = resolve_lab_settings("lab-2", key, &why);
  ASSERT_TRUE(s) << why;
  EXPECT_NE(lab_settings_text(*s).find("lab 'lab-2'; messages signed with key 0x"), std::string::npos);
}

// Changing the key (docs/security.md): --key NEW,OLD signs with the first and accepts both; under
// systemd the credential lab-key-previous is accepted too. One unreadable file refuses them all.
TEST(LabKey, SeveralKeysWhileTheKeyChanges) {
  TempDir d;
  const std::string next = d.write("new.key", std::string(32, 'n'));
  const std::string old = d.write("old.key", std::string(32, 'o'));
  const LabKeyChoice both = choose_lab_key(next + "," + old, std::nullopt);
  ASSERT_TRUE(both.key) << both.error;
  ASSERT_EQ(both.also_accepted.size(), 1u);
  EXPECT_EQ(both.key->id, choose_lab_key(next, std::nullopt).key->id);
  EXPECT_EQ(both.also_accepted[0].id, choose_lab_key(old, std::nullopt).key->id);
  const LabKeyChoice missing = choose_lab_key(next + "," + (d.path / "gone.key").string(), std::nullopt);
  EXPECT_FALSE(missing.key);
  EXPECT_NE(missing.error.find("gone.key"), std::string::npos) << missing.error;
  d.write(lab_key_credential, std::string(32, 'n'));
  d.write(lab_key_previous_credential, std::string(32, 'o'));
  const LabKeyChoice cred = choose_lab_key("", d.path.string());
  ASSERT_TRUE(cred.key);
  ASSERT_EQ(cred.also_accepted.size(), 1u);
  EXPECT_EQ(cred.also_accepted[0].id, both.also_accepted[0].id);
  std::string why;
  const auto s = resolve_lab_settings("lab", next + "," + old, &why);
  ASSERT_TRUE(s) << why;
  EXPECT_NE(lab_settings_text(*s).find("also accepted while keys change"), std::string::npos) << lab_settings_text(*s);
}

}  // namespace
}  // namespace spindown
