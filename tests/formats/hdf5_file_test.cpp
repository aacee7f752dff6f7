// The HDF5 layer itself (formats/hdf5_file.hpp): round trips of datasets, strings, series and
// attributes, and the typed errors for missing objects, wrong dtypes and shapes and broken files,
// each naming the file and the dataset or attribute path.
#include "sinew/formats/hdf5_file.hpp"

#include <sys/stat.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "sinew/common/error.hpp"
#include "test_models.hpp"

namespace sinew::formats::hdf5 {
namespace {

using testing::file_bytes;
using testing::temp_path;

// The message of the exception E that `f` throws ("" and a failure when none or another type).
template <typename E, typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected exception type: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no exception";
  return "";
}

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "in: " << (text)

// A file with one of everything, written through the layer.
std::string write_sample() {
  const auto path = temp_path("sample.h5");
  auto f = create_file(path);
  set_attribute(f, "format", std::string("sample"), path);
  set_attribute(f, "label", std::string("utf-8 é"), path, StringKind::variable);
  set_attribute(f, "empty", std::string(), path);
  set_attribute(f, "version", std::int64_t{7}, path);
  set_attribute(f, "small", std::int32_t{-3}, path);
  set_attribute(f, "scale", 0.25, path);
  create_group(f, "/data", path);
  const std::vector<double> xyz{1, 2, 3, 4, 5, 6};
  write(f, "/data/xyz", {2, 3}, xyz.data(), path);
  const std::vector<std::int32_t> ids{5, -1, 7};
  write(f, "/data/ids", {3}, ids.data(), path);
  const std::vector<std::int64_t> big{std::int64_t{1} << 40};
  write(f, "/data/big", {1}, big.data(), path);
  const std::vector<std::uint8_t> bytes{0, 255};
  write(f, "/data/bytes", {2}, bytes.data(), path);
  const std::vector<float> none;
  write(f, "/data/none", {0, 3}, none.data(), path);
  const double h = 1e-3;
  write(f, "/data/h", {}, &h, path);
  write_strings(f, "/data/names", {"skin", "", "fat"}, path);
  write_string(f, "/data/note", "one line", path);
  close_file(f, path);
  return path;
}

TEST(Hdf5File, DatasetsRoundTrip) {
  const auto path = write_sample();
  auto f = open_checked(path);
  EXPECT_EQ(read_array<double>(f, "/data/xyz", path, 3), (std::vector<double>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(read_array<std::int32_t>(f, "/data/ids", path), (std::vector<std::int32_t>{5, -1, 7}));
  EXPECT_EQ(read_array<std::int64_t>(f, "/data/big", path).at(0), std::int64_t{1} << 40);
  EXPECT_EQ(read_array<std::uint8_t>(f, "/data/bytes", path), (std::vector<std::uint8_t>{0, 255}));
  EXPECT_TRUE(read_array<float>(f, "/data/none", path, 3).empty());
  EXPECT_EQ(read_scalar<double>(f, "/data/h", path), 1e-3);
  EXPECT_EQ(read_strings(f, "/data/names", path), (std::vector<std::string>{"skin", "", "fat"}));
  EXPECT_EQ(read_string(f, "/data/note", path), "one line");
  EXPECT_EQ(shape(f, "/data/xyz", path), (std::vector<hsize_t>{2, 3}));
  EXPECT_TRUE(shape(f, "/data/h", path).empty());
  // The converting read: any numeric dtype, any shape, optionally an exact count.
  EXPECT_EQ(read<float>(f, "/data/ids", path), (std::vector<float>{5, -1, 7}));
  EXPECT_EQ(read<double>(f, "/data/xyz", path, 6).size(), 6u);
  EXPECT_EQ(members(f, "/data", path).size(), 8u);
  EXPECT_TRUE(exists(f, "/data/xyz"));
  EXPECT_FALSE(exists(f, "/data/nothing"));
  EXPECT_FALSE(exists(f, "/nowhere/at/all"));
}

TEST(Hdf5File, AttributesRoundTrip) {
  const auto path = write_sample();
  auto f = open_file(path, false);
  EXPECT_EQ(string_attribute(f, "format", path), "sample");
  EXPECT_EQ(string_attribute(f, "label", path), "utf-8 é");
  EXPECT_EQ(string_attribute(f, "empty", path), "");
  EXPECT_EQ(int_attribute(f, "version", path), 7);
  EXPECT_EQ(int_attribute(f, "small", path), -3);
  EXPECT_EQ(double_attribute(f, "scale", path), 0.25);
  EXPECT_EQ(double_attribute(f, "version", path), 7.0);  // an integer is a number
  EXPECT_TRUE(has_attribute(f, "format"));
  EXPECT_FALSE(has_attribute(f, "nothing"));
}

TEST(Hdf5File, OrderedGroupsListInCreationOrder) {
  const auto path = temp_path("ordered.h5");
  {
    auto f = create_file(path);
    create_group(f, "/sets", path, true);
    create_group(f, "/plain", path);
    const std::int32_t one = 1;
    for (const char* name : {"zeta", "alpha", "mid"}) {
      write(f, std::string("/sets/") + name, {1}, &one, path);
      write(f, std::string("/plain/") + name, {1}, &one, path);
    }
  }
  auto f = open_file(path, false);
  EXPECT_EQ(members(f, "/sets", path), (std::vector<std::string>{"zeta", "alpha", "mid"}));
  EXPECT_EQ(members(f, "/plain", path), (std::vector<std::string>{"alpha", "mid", "zeta"}));
}

TEST(Hdf5File, SeriesGrowAndShrink) {
  const auto path = temp_path("series.h5");
  {
    auto f = create_file(path);
    auto ds = create_series<double>(f, "/x", {2}, path);
    const double a[2] = {1, 2}, b[2] = {3, 4}, c[2] = {5, 6};
    append(ds.get(), 0, a, path, "/x");
    append(ds.get(), 1, b, path, "/x");
    append(ds.get(), 2, c, path, "/x");
    flush(f, path);
    set_frames(ds, 2, path, "/x");
  }
  auto f = open_file(path, true);
  EXPECT_EQ(shape(f, "/x", path), (std::vector<hsize_t>{2, 2}));
  EXPECT_EQ(read<double>(f, "/x", path), (std::vector<double>{1, 2, 3, 4}));
}

TEST(Hdf5File, SameDataGiveIdenticalBytes) {
  const auto first = file_bytes(write_sample());
  EXPECT_EQ(file_bytes(write_sample()), first);  // no object time stamps
}

TEST(Hdf5File, MissingObjectsNameTheirPath) {
  const auto path = write_sample();
  auto f = open_file(path, false);
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_array<double>(f, "/data/nope", path); }),
                  path + ": /data/nope: missing dataset");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read<double>(f, "/gone/deeper", path); }),
                  "/gone/deeper: missing dataset");
  EXPECT_CONTAINS(error_of<FormatError>([&] { members(f, "/gone", path); }),
                  "/gone: missing group");
  EXPECT_CONTAINS(error_of<FormatError>([&] { string_attribute(f, "nothing", path); }),
                  path + ": /nothing: missing attribute");
  auto g = open_group(f, "/data", path);
  EXPECT_CONTAINS(error_of<FormatError>([&] { int_attribute(g, "nothing", path); }),
                  "/data/nothing: missing attribute");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_array<double>(f, "/data", path); }),
                  "/data: cannot open, not a dataset");
}

TEST(Hdf5File, WrongTypesAndShapesAreFormatErrors) {
  const auto path = write_sample();
  auto f = open_file(path, false);
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_array<std::int32_t>(f, "/data/xyz", path, 3); }),
                  "/data/xyz: wrong dtype, expected int32");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_array<std::int64_t>(f, "/data/ids", path); }),
                  "/data/ids: wrong dtype, expected int64");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_array<std::int32_t>(f, "/data/bytes", path); }),
                  "/data/bytes: wrong dtype, expected int32");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_array<double>(f, "/data/xyz", path, 8); }),
                  "/data/xyz: wrong shape (2, 3), expected (n, 8)");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_array<double>(f, "/data/xyz", path); }),
                  "/data/xyz: wrong shape (2, 3), expected (n)");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_scalar<double>(f, "/data/xyz", path); }),
                  "/data/xyz: wrong shape (2, 3), expected scalar");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_strings(f, "/data/ids", path); }),
                  "/data/ids: wrong dtype, expected string");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_string(f, "/data/names", path); }),
                  "/data/names: wrong shape (3), expected scalar");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read<double>(f, "/data/xyz", path, 5); }),
                  "/data/xyz: expected 5 values, found 6");
  EXPECT_CONTAINS(error_of<FormatError>([&] { string_attribute(f, "version", path); }),
                  "/version: must be one string");
  EXPECT_CONTAINS(error_of<FormatError>([&] { int_attribute(f, "format", path); }),
                  "/format: must be one integer");
  EXPECT_CONTAINS(error_of<FormatError>([&] { double_attribute(f, "format", path); }),
                  "/format: must be one number");
}

TEST(Hdf5File, BrokenFilesGiveTypedErrors) {
  const auto missing = temp_path("missing.h5");
  EXPECT_CONTAINS(error_of<IoError>([&] { open_checked(missing); }), missing + ": cannot open");
  EXPECT_CONTAINS(error_of<IoError>([&] { open_file(missing, false); }),
                  missing + ": cannot open the file: No such file or directory");
  // A FIFO with no writer blocked H5Fopen for good (scripts/fuzz_inputs.py); a folder and a FIFO
  // are IoErrors saying what they are, and is_hdf5 does not read them.
  const auto fifo = temp_path("fifo.h5");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_FALSE(is_hdf5(fifo));
  EXPECT_CONTAINS(error_of<IoError>([&] { open_checked(fifo); }),
                  fifo + ": the file is a FIFO (named pipe), not a regular file");
  EXPECT_CONTAINS(error_of<IoError>([&] { open_file(fifo, false); }),
                  fifo + ": the file is a FIFO");
  std::filesystem::remove(fifo);
  const auto folder = temp_path("folder.h5");
  std::filesystem::create_directory(folder);
  EXPECT_CONTAINS(error_of<IoError>([&] { open_checked(folder); }),
                  folder + ": the file is a folder, not a regular file");
  std::filesystem::remove(folder);
  const auto text = temp_path("text.h5");
  std::ofstream(text) << "not hdf5 at all";
  EXPECT_FALSE(is_hdf5(text));
  EXPECT_CONTAINS(error_of<FormatError>([&] { open_checked(text); }), text + ": not an HDF5 file");
  EXPECT_CONTAINS(error_of<IoError>([&] { create_file("/nonexistent-dir-sinew/x.h5"); }),
                  "/nonexistent-dir-sinew/x.h5: cannot create the file");
  // Every truncation of a good file: a typed error or a clean read, never a crash.
  const auto good = file_bytes(write_sample());
  const auto cut = temp_path("cut.h5");
  for (std::size_t n = 0; n < good.size(); n += 97) {
    std::ofstream(cut, std::ios::binary | std::ios::trunc)
        .write(good.data(), static_cast<std::streamsize>(n));
    try {
      auto f = open_checked(cut);
      (void)read_array<double>(f, "/data/xyz", cut, 3);
      (void)read_strings(f, "/data/names", cut);
      (void)string_attribute(f, "label", cut);
    } catch (const Error& e) {
      EXPECT_CONTAINS(e.what(), cut);
    }
  }
}

// The global heap (variable-length strings) has no checksum and HDF5 follows it blindly (one
// flipped byte of a model file once segfaulted H5HG_read): the readers check it first.
TEST(Hdf5File, DamagedGlobalHeapIsAFormatError) {
  const auto sample = write_sample();
  const auto good = file_bytes(sample);
  const auto heap = good.find("GCOL");
  ASSERT_NE(heap, std::string::npos);
  haddr_t names_at = HADDR_UNDEF;
  {
    auto f = open_checked(sample);
    Handle ds(H5Dopen2(f, "/data/names", H5P_DEFAULT), H5Dclose);
    names_at = H5Dget_offset(ds);
  }
  ASSERT_NE(names_at, HADDR_UNDEF);
  const auto damaged = temp_path("damaged.h5");
  const auto write_with = [&](std::size_t at, const std::string& bytes) {
    auto b = good;
    b.replace(at, bytes.size(), bytes);
    std::ofstream(damaged, std::ios::binary | std::ios::trunc)
        .write(b.data(), static_cast<std::streamsize>(b.size()));
  };
  // The first object's size (after the 16-byte collection header: index, count, reserved, size).
  write_with(heap + 16 + 8, std::string(8, '\xff'));
  {
    auto f = open_checked(damaged);
    EXPECT_CONTAINS(error_of<FormatError>([&] { read_strings(f, "/data/names", damaged); }),
                    damaged + ": /data/names: string 0: its global heap collection");
    EXPECT_CONTAINS(error_of<FormatError>([&] { string_attribute(f, "label", damaged); }),
                    "/label: the global heap collection at byte");
  }
  // The first string's object index (after its length and the collection's address).
  write_with(static_cast<std::size_t>(names_at) + 4 + 8, std::string("\x39\x05\0\0", 4));
  {
    auto f = open_checked(damaged);
    EXPECT_CONTAINS(error_of<FormatError>([&] { read_strings(f, "/data/names", damaged); }),
                    "string 0: its heap reference (collection");
    EXPECT_EQ(string_attribute(f, "label", damaged), "utf-8 é");  // its own reference is intact
  }
  // A length that disagrees with the object (HDF5 would copy the object into a shorter buffer).
  write_with(static_cast<std::size_t>(names_at), std::string("\x02\0\0\0", 4));
  {
    auto f = open_checked(damaged);
    EXPECT_CONTAINS(error_of<FormatError>([&] { read_strings(f, "/data/names", damaged); }),
                    "string 0: its heap reference");
  }
}

// A file in the earliest format (version 1 object headers, no checksums: sinew's files before the
// 1.8+ format, other tools' by default): a damaged heap reference of a variable-length attribute,
// which HDF5 would follow into a crash, is found in the header and refused.
TEST(Hdf5File, DamagedAttributeReferenceInAnOldFormatHeader) {
  const auto path = temp_path("old.h5");
  {
    Handle f(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    ASSERT_TRUE(f.valid());
    set_attribute(f, "label", std::string("utf-8 é"), path, StringKind::variable);
  }
  const auto good = file_bytes(path);
  ASSERT_EQ(good.find("OHDR"), std::string::npos) << "not the earliest format";
  const auto heap = good.find("GCOL");
  ASSERT_NE(heap, std::string::npos);
  // The reference: length 8 (the UTF-8 bytes of "utf-8 é"), the collection's address, the index.
  std::string reference("\x08\0\0\0", 4);
  for (int k = 0; k < 8; ++k) reference += static_cast<char>((heap >> (8 * k)) & 0xff);
  const auto at = good.find(reference);
  ASSERT_NE(at, std::string::npos);
  {
    auto f = open_checked(path);
    EXPECT_EQ(string_attribute(f, "label", path), "utf-8 é");
  }
  auto b = good;
  b[at + 12] = static_cast<char>(0x39);  // object 0x39 does not exist
  const auto damaged = temp_path("damaged.h5");
  std::ofstream(damaged, std::ios::binary | std::ios::trunc)
      .write(b.data(), static_cast<std::streamsize>(b.size()));
  auto f = open_checked(damaged);
  EXPECT_CONTAINS(error_of<FormatError>([&] { string_attribute(f, "label", damaged); }),
                  damaged + ": /label: its heap reference (collection");
}

// In the earliest format a variable-length string's datatype (class 9, string, base type of
// 1-byte characters) is not checksummed either: a base type size damaged to 2^30 made HDF5 1.10
// allocate and clear 2^30 bytes per character (57 s for one attribute, a fuzz case). Both an
// attribute's and a dataset's datatype are checked in the header and refused at once.
TEST(Hdf5File, DamagedStringDatatypeInAnOldFormatHeader) {
  const auto path = temp_path("old_types.h5");
  {
    Handle f(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    ASSERT_TRUE(f.valid());
    set_attribute(f, "label", std::string("sinew-model"), path, StringKind::variable);
    write_strings(f, "/names", {"skin", "skull"}, path);
  }
  auto b = file_bytes(path);
  ASSERT_EQ(b.find("OHDR"), std::string::npos) << "not the earliest format";
  {
    auto f = open_checked(path);
    EXPECT_EQ(string_attribute(f, "label", path), "sinew-model");
    EXPECT_EQ(read_strings(f, "/names", path), (std::vector<std::string>{"skin", "skull"}));
  }
  // The vlen datatype's size (16) and then the base type: fixed-point, 1 byte, 8-bit precision.
  const std::string base("\x10\0\0\0\x10\0\0\0\x01\0\0\0\0\0\x08\0", 16);
  int patched = 0;
  for (auto at = b.find(base); at != std::string::npos; at = b.find(base, at + 1), ++patched) {
    b[at + 11] = static_cast<char>(0x40);  // base size 1 → 2^30 + 1
  }
  ASSERT_EQ(patched, 2) << "expected the attribute's and the dataset's datatype";
  const auto damaged = temp_path("damaged_types.h5");
  std::ofstream(damaged, std::ios::binary | std::ios::trunc)
      .write(b.data(), static_cast<std::streamsize>(b.size()));
  auto f = open_checked(damaged);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_CONTAINS(error_of<FormatError>([&] { string_attribute(f, "label", damaged); }),
                  damaged +
                      ": /label: its datatype is damaged (a variable-length string of "
                      "1073741825-byte characters)");
  EXPECT_CONTAINS(error_of<FormatError>([&] { read_strings(f, "/names", damaged); }),
                  "/names: its datatype is damaged");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
}

// An attribute message whose dataspace size has its high byte flipped (e.g. 4 → 46,084) puts the value past the
// message's end: HDF5 1.10 copied the value from out of bounds when looking the attribute up (a
// segfault in H5Aexists) or read a string descriptor out of other bytes and spent 21 s clearing a
// conversion buffer for it (fuzz cases in the earliest format). Refused when the file is opened.
TEST(Hdf5File, AttributeMessageOverrunInAnOldFormatHeader) {
  const auto path = temp_path("old_overrun.h5");
  {
    Handle f(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    ASSERT_TRUE(f.valid());
    set_attribute(f, "label", std::string("sinew-model"), path, StringKind::variable);
  }
  auto b = file_bytes(path);
  const auto name = b.find(std::string("label\0", 6));
  ASSERT_NE(name, std::string::npos);
  ASSERT_EQ(b[name - 1], 0) << "the dataspace's size (a few bytes) ends before the name";
  b[name - 1] = static_cast<char>(0xb4);  // its high byte: + 46,080 bytes
  const auto damaged = temp_path("damaged_overrun.h5");
  std::ofstream(damaged, std::ios::binary | std::ios::trunc)
      .write(b.data(), static_cast<std::streamsize>(b.size()));
  const auto t0 = std::chrono::steady_clock::now();
  const auto message = error_of<FormatError>([&] {
    auto f = open_checked(damaged);
    (void)string_attribute(f, "label", damaged);
  });
  EXPECT_CONTAINS(message, damaged + ": /: attribute message 0 of its header is damaged");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
}

// Files are written in the 1.8+ format, whose object headers carry checksums: a flipped byte in
// the root group's header is refused instead of followed.
TEST(Hdf5File, ObjectHeadersAreChecksummed) {
  const auto good = file_bytes(write_sample());
  const auto header = good.find("OHDR");
  ASSERT_NE(header, std::string::npos) << "no version 2 object header: not the 1.8+ format";
  auto b = good;
  b[header + 20] = static_cast<char>(b[header + 20] ^ 0x10);
  const auto damaged = temp_path("damaged.h5");
  std::ofstream(damaged, std::ios::binary | std::ios::trunc)
      .write(b.data(), static_cast<std::streamsize>(b.size()));
  const auto message = error_of<FormatError>([&] {
    auto f = open_checked(damaged);
    (void)string_attribute(f, "format", damaged);
  });
  EXPECT_CONTAINS(message, damaged);
}

}  // namespace
}  // namespace sinew::formats::hdf5
