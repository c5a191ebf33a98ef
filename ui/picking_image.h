// The panorama a user picks in (points to align scans, targets): the scan's reflectance, or for
// scans without it (every return the same value) the range, near bright and far dark, so that the
// scene's shapes show. One pixel per cell: pixel (x, y) is cell (row y, column x).
#pragma once

#include <QImage>
#include <QPointF>
#include <optional>

#include "core/geometry/scan.h"

namespace scanreg::ui {

QImage PickingImage(const Scan& scan);

// The cell with a return nearest a click at `pixel` (column, row), within `snap` pixels; none when
// there is none (sky or a gap).
std::optional<std::pair<int, int>> SnapToCell(const Scan& scan, QPointF pixel, int snap);

}  // namespace scanreg::ui
