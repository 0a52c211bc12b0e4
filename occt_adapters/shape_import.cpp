#include "occt_adapters/shape_import.h"

#include "occt_adapters/occt_errors.h"
#include "occt_adapters/leak_check_pause.h"
#include "occt_adapters/shape_impl.h"

#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <STEPControl_Reader.hxx>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <filesystem>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <unistd.h>

namespace gk::occt {
namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext.empty() ? ext : ext.substr(1);
}

// OCCT's readers print statistics to stdout by default: keep them quiet.
void silence_occt_messages() {
  static std::atomic<bool> done{false};
  if (done.exchange(true)) return;
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer));
}

// OCCT's data-exchange controllers register their static parameters on the first reader of each
// kind and keep them for the life of the process (never freed, by design). The first construction
// happens with leak checking paused, so LeakSanitizer reports what we leak and not that.
template <typename Reader>
void register_reader_once() {
  static std::once_flag once;
  std::call_once(once, [] {
    const LeakCheckPause pause;
    Reader warm_up;
  });
}

template <typename Reader>
Result<Shape> read_with_xs_reader(const std::string& path, const char* kind) {
  register_reader_once<Reader>();
  TopoDS_Shape shape;
  IFSelect_ReturnStatus status = IFSelect_RetVoid;
  auto ran = guarded(path, std::string("reading ") + kind, [&] {
    Reader reader;
    status = reader.ReadFile(path.c_str());
    if (status != IFSelect_RetDone) return;
    reader.TransferRoots();
    shape = reader.OneShape();
  });
  if (!ran.ok()) return ran.error();
  if (status != IFSelect_RetDone) return invalid_argument(path, std::string("not a readable ") + kind + " file");
  if (shape.IsNull()) return invalid_argument(path, std::string(kind) + " file holds no shape");
  return wrap(shape);
}

// OCCT's BREP reader allocates each table ("Locations 2000000000") before reading it: an 84-byte
// file kept it busy for 12 s. Every table entry takes at least one byte, so a count above the
// file's size is refused before OCCT sees it.
Result<bool> check_brep_tables(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return invalid_argument(path, "cannot read the file");
  std::ifstream in(path);
  std::string line;
  static const char* const tables[] = {"Locations", "Curve2ds", "Curves", "Polygon3D", "PolygonOnTriangulations",
                                       "Surfaces", "Triangulations", "TShapes"};
  while (std::getline(in, line)) {
    for (const char* table : tables) {
      const std::size_t n = std::strlen(table);
      if (line.compare(0, n, table) != 0 || line.size() <= n || line[n] != ' ') continue;
      const long long count = std::atoll(line.c_str() + n + 1);
      if (count < 0 || static_cast<unsigned long long>(count) > size)
        return invalid_argument(path, std::string("declares ") + std::to_string(count) + " " + table + " in a file of " +
                                          std::to_string(size) + " bytes");
    }
  }
  return true;
}

Result<Shape> read_brep(const std::string& path) {
  if (auto checked = check_brep_tables(path); !checked.ok()) return checked.error();
  TopoDS_Shape shape;
  bool ok = false;
  auto ran = guarded(path, "reading BREP", [&] {
    BRep_Builder builder;
    ok = BRepTools::Read(shape, path.c_str(), builder);
  });
  if (!ran.ok()) return ran.error();
  if (!ok || shape.IsNull()) return invalid_argument(path, "not a readable BREP file");
  return wrap(shape);
}

}  // namespace

Result<Shape> read_shape_file(const std::string& path) {
  silence_occt_messages();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return invalid_argument(path, "no such file");
  if (std::filesystem::file_size(path, ec) == 0) return invalid_argument(path, "file is empty");
  const std::string ext = lower_extension(path);
  Result<Shape> shape = invalid_argument(path, "unknown CAD format '" + ext + "' (expected step, stp, brep, igs, iges)");
  if (ext == "step" || ext == "stp") shape = read_with_xs_reader<STEPControl_Reader>(path, "STEP");
  else if (ext == "igs" || ext == "iges") shape = read_with_xs_reader<IGESControl_Reader>(path, "IGES");
  else if (ext == "brep") shape = read_brep(path);
  if (!shape.ok()) return shape;
  if (shape.value().face_count() == 0) return invalid_argument(path, "shape has no faces");
  return shape;
}

Result<Shape> read_shape_bytes(const std::string& bytes, const std::string& format) {
  if (bytes.empty()) return invalid_argument("bytes", "empty CAD payload");
  // The STEP and IGES readers take files: stage the bytes in a private temporary file.
  static std::atomic<long> counter{0};
  const auto dir = std::filesystem::temp_directory_path();
  const std::string path =
      (dir / ("gk-import-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "." + format)).string();
  {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) return invalid_argument("bytes", "cannot stage the payload in " + dir.string());
  }
  auto shape = read_shape_file(path);
  std::error_code ec;
  std::filesystem::remove(path, ec);
  if (!shape.ok()) return invalid_argument("bytes (" + format + ")", shape.error().message);
  return shape;
}

}  // namespace gk::occt
