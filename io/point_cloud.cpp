// SPDX-License-Identifier: MIT
#include "io/point_cloud.h"

#include <fmt/format.h>

#include <cmath>
#include <string>
#include <vector>

#include "framework/error.h"
#include "io/file_reading.h"
#include "io/ply_reader.h"
#include "io/raw_mesh.h"
#include "io/text_scanning.h"

namespace harap {

using namespace io_internal;

bool IsPointCloudFile(const std::filesystem::path& file) {
  const std::string extension = DetectFormat(file).extension;
  return extension == "xyz" || extension == "pts" || extension == "txt";
}

bool HoldsPointCloud(const std::filesystem::path& file) {
  if (IsPointCloudFile(file)) return true;
  if (DetectFormat(file).extension != "ply") return false;
  return !PlyDeclaresFaces(ReadFileMaybeXz(file), file.string());
}

PointCloud ParsePointCloudText(std::string_view data, const std::string& what) {
  LineReader lines(data);
  std::string_view line;
  std::vector<double> points, normals;
  int columns = 0;  // fixed by the first point
  while (lines.NextContent(line)) {
    double values[6];
    int count = 0;
    for (std::string_view token = NextToken(line); !token.empty(); token = NextToken(line)) {
      if (count == 6 || !ParseDouble(token, values[count])) {
        throw InputError(fmt::format("{}:{}: a point is `x y z` or `x y z nx ny nz`; {} is {}",
                                     what, lines.line_number(), Quote(token),
                                     count == 6 ? "a seventh value" : "not a number"));
      }
      ++count;
    }
    if (columns == 0) columns = count;
    if (count != 3 && count != 6) {
      throw InputError(fmt::format("{}:{}: {} values; a point is `x y z` or `x y z nx ny nz`", what,
                                   lines.line_number(), count));
    }
    if (count != columns) {
      throw InputError(fmt::format("{}:{}: {} values, but the first point has {}", what,
                                   lines.line_number(), count, columns));
    }
    for (int k = 0; k < count; ++k) {
      if (!std::isfinite(values[k])) {
        throw InputError(fmt::format("{}:{}: value {} is not finite ({})", what,
                                     lines.line_number(), k + 1, values[k]));
      }
    }
    points.insert(points.end(), values, values + 3);
    if (count == 6) normals.insert(normals.end(), values + 3, values + 6);
  }
  if (points.empty()) throw InputError(fmt::format("{}: no points", what));
  PointCloud cloud;
  cloud.points = ToPositions(points);
  if (!normals.empty()) cloud.normals = ToPositions(normals);
  return cloud;
}

PointCloud ReadPointCloud(const std::filesystem::path& file) {
  const std::string what = file.string();
  const FileFormat format = DetectFormat(file);
  if (format.extension == "ply") return ParsePlyPoints(ReadFileMaybeXz(file), what);
  if (!IsPointCloudFile(file)) {
    throw InputError(fmt::format(
        "{}: unknown point cloud extension '.{}'; supported: .xyz, .pts, .txt (x y z [nx ny "
        "nz] per line) and .ply (its vertices), each optionally .xz-compressed",
        what, format.extension));
  }
  return ParsePointCloudText(ReadFileMaybeXz(file), what);
}

}  // namespace harap
