#pragma once
// A file path in the test temp directory, unique per process and name,
// removed when the object goes out of scope (the file may never be made).
#include <unistd.h>

#include <cstdio>
#include <string>

#include <gtest/gtest.h>

namespace rtfuse::test {

class TempFile {
 public:
  TempFile(const std::string& name, const std::string& suffix)
      : path_(testing::TempDir() + "rtfuse_" + name + "_" + std::to_string(::getpid()) + suffix) {}
  ~TempFile() { std::remove(path_.c_str()); }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace rtfuse::test
