#pragma once
// The bytes of an input file, viewed as text without a copy: a regular file is mapped
// read-only and its pages read in at once (MAP_POPULATE); anything else (a pipe, a
// process substitution) is read into memory. A million-body model's 460 MB are viewed in
// 0.2 s where reading them into a string took 1-2 s (the string's pages zeroed and
// faulted in, then copied into) on a 2-core VM.
//
// The mapping is shared with the page cache: a file truncated by another program while
// it is mapped would fault (SIGBUS) on the lost pages. Hold a FileText only while the text
// is parsed.
#include <cstddef>
#include <string>
#include <string_view>

namespace mbsflow {

class FileText {
 public:
  // InputError("path: cannot open the WHAT") if it cannot be read, or if it is larger
  // than max_bytes (checked before anything is read).
  FileText(const std::string& path, const std::string& what, std::size_t max_bytes);
  ~FileText();
  FileText(const FileText&) = delete;
  FileText& operator=(const FileText&) = delete;

  std::string_view text() const { return mapped_ ? std::string_view(mapped_, size_) : std::string_view(read_); }

 private:
  const char* mapped_ = nullptr;
  std::size_t size_ = 0;
  std::string read_;  // when not mapped
};

// A model file's text, checked for size as read_model_file does.
FileText map_model_file(const std::string& path);

}  // namespace mbsflow
