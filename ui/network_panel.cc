#include "ui/network_panel.h"

#include <QContextMenuEvent>
#include <QGraphicsEllipseItem>
#include <QGraphicsLineItem>
#include <QGraphicsPolygonItem>
#include <QGraphicsSimpleTextItem>
#include <QHelpEvent>
#include <QMenu>
#include <QToolTip>
#include <algorithm>
#include <map>
#include <cmath>

#include "core/common/skipped_pair.h"
#include "core/io/project_tree.h"
#include "ui/scan_cloud_actors.h"

namespace scanreg::ui {
namespace {

constexpr double kNodeRadius = 9.0;  // screen pixels at any zoom
// Past this many scans (a campaign of a street or a city) nodes are drawn smaller and only the scans
// that need the user's eye are labelled (root, unregistered, hand-placed, overridden); every scan
// still names itself in its tooltip.
constexpr int kLabelAllUpTo = 30;
constexpr double kSmallNodeRadius = 5.0;

// Node positions in scene units: registered scans at their x/y (y up on screen), others on a circle.
// Top view of the registered scans: world (x, y) to scene units (600 across the registered extent).
struct TopView {
  double min_x = 0, min_y = 0, scale = 1;
  bool valid = false;  // at least two registered scans
  QPointF Map(const Eigen::Vector3d& p) const { return QPointF((p.x() - min_x) * scale, -(p.y() - min_y) * scale); }
};

std::vector<QPointF> Layout(const io::Project& project, TopView* view) {
  const int n = static_cast<int>(project.scans.size());
  std::vector<QPointF> pos(n);
  double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300;
  int registered = 0;
  for (const io::ProjectScan& s : project.scans) {
    if (!s.registered) continue;
    ++registered;
    const Eigen::Vector3d t = s.world_from_scan.translation();
    min_x = std::min(min_x, t.x()), max_x = std::max(max_x, t.x());
    min_y = std::min(min_y, t.y()), max_y = std::max(max_y, t.y());
  }
  const double extent = std::max({max_x - min_x, max_y - min_y, 1e-6});
  const double scale = registered >= 2 ? 600.0 / extent : 1.0;
  *view = TopView{min_x, min_y, scale, registered >= 2};
  int k = 0;
  // Clusters (scans registered to each other, not to the root) to the right, in their own frame.
  double cluster_x = 750;
  std::map<std::string, QPointF> cluster_origin;
  for (int i = 0; i < n; ++i) {
    const io::ProjectScan& s = project.scans[i];
    if (s.registered && registered >= 2) {
      pos[i] = view->Map(s.world_from_scan.translation());
    } else if (!s.registered && !s.cluster.empty() && project.FindScan(s.cluster) >= 0) {
      const Eigen::Vector3d root = project.scans[project.FindScan(s.cluster)].world_from_scan.translation();
      if (!cluster_origin.count(s.cluster)) {
        cluster_origin[s.cluster] = QPointF(cluster_x, 300);
        cluster_x += 300;
      }
      const Eigen::Vector3d t = s.world_from_scan.translation() - root;
      const double cs = registered >= 2 ? scale : 20.0;
      pos[i] = cluster_origin[s.cluster] + QPointF(t.x() * cs, -t.y() * cs);
    } else {
      const double a = 2 * M_PI * k++ / std::max(1, n);
      pos[i] = QPointF(750 + 150 * std::cos(a), 150 * std::sin(a));
    }
  }
  return pos;
}

double DistanceToSegment(QPointF p, QPointF a, QPointF b) {
  const QPointF ab = b - a;
  const double len2 = QPointF::dotProduct(ab, ab);
  const double t = len2 > 0 ? std::clamp(QPointF::dotProduct(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  const QPointF q = a + t * ab - p;
  return std::hypot(q.x(), q.y());
}

}  // namespace

NetworkPanel::NetworkPanel(QWidget* parent) : ZoomView(parent) {
  setObjectName("ScanNetwork");
  setScene(new QGraphicsScene(this));
  setBackgroundBrush(palette().base());
  setMinimumSize(240, 200);
  SetMargin(30);  // nodes and labels are drawn at screen size around their positions
}

void NetworkPanel::Show(const io::Project& project) {
  project_ = project;
  QGraphicsScene* s = scene();
  s->clear();
  nodes_ = edges_ = targets_ = 0;
  TopView view;
  pos_ = Layout(project, &view);
  const std::vector<bool> on_hand = io::RestsOnHandPlacement(project);
  for (std::size_t k = 0; k < project.links.size(); ++k) {
    const io::LinkRecord& l = project.links[k];
    const int a = project.FindScan(l.parent), b = project.FindScan(l.child);
    if (a < 0 || b < 0) continue;
    QPen pen(Qt::gray, 1.5, Qt::DashLine);
    if (!l.loop_check) {
      if (l.status == io::LinkStatus::kOk) pen = QPen(QColor(40, 170, 70), 3.5);
      if (l.status == io::LinkStatus::kWeak) pen = QPen(QColor(240, 150, 30), 3.5);
      if (l.status == io::LinkStatus::kFailed) pen = QPen(QColor(200, 50, 40), 1.5, Qt::DashLine);
    }
    if (l.user_rejected) pen = QPen(QColor(120, 0, 0), 2, Qt::DotLine);
    pen.setCosmetic(true);  // the same width at any zoom
    auto* line = s->addLine(QLineF(pos_[a], pos_[b]), pen);
    line->setZValue(l.status == io::LinkStatus::kFailed ? -2 : -1);
    line->setData(0, static_cast<int>(k));
    ++edges_;
  }
  const bool many = static_cast<int>(project.scans.size()) > kLabelAllUpTo;
  node_radius_ = many ? kSmallNodeRadius : kNodeRadius;
  const double r = node_radius_;
  for (int i = 0; i < static_cast<int>(project.scans.size()); ++i) {
    const io::ProjectScan& scan = project.scans[i];
    double rgb[3];
    ScanColour(i, rgb);
    QPen outline(scan.registered ? QColor(30, 30, 30) : QColor(200, 50, 40), scan.registered ? 1.5 : 3);
    if (!scan.registered && scan.unverified) outline = QPen(QColor(240, 150, 30), 3);  // placed, waiting for the user
    if (on_hand[i]) outline = QPen(QColor(230, 120, 0), 3, Qt::DashLine);  // rests on a hand placement
    outline.setCosmetic(true);
    auto* node = s->addEllipse(-r, -r, 2 * r, 2 * r, outline,
                               QBrush(QColor::fromRgbF(rgb[0], rgb[1], rgb[2])));
    node->setFlag(QGraphicsItem::ItemIgnoresTransformations);
    node->setPos(pos_[i]);
    QString text = QString::fromStdString(scan.name);
    if (project.root == scan.name) text += tr(" (root)");
    if (on_hand[i]) text += tr(" (hand)");
    if (!scan.registered && scan.unverified) text += tr(" (not verified)");
    if (!scan.registered && !scan.cluster.empty()) text += tr(" [cluster %1]").arg(QString::fromStdString(scan.cluster));
    if (scan.parent_override) text += " ✎";
    ++nodes_;
    if (many && project.root != scan.name && !on_hand[i] && scan.registered && !scan.parent_override) continue;
    auto* label = s->addSimpleText(text);
    label->setFlag(QGraphicsItem::ItemIgnoresTransformations);
    label->setPos(pos_[i]);
    label->setTransform(QTransform::fromTranslate(r + 2, -r - 14));
    label->setBrush(palette().text());
  }
  // Targets (issue 15): where the registered scans that saw them put them, one mark per target
  // (the mean of its observations); tied to control blue, others grey, red beyond 1 cm residual.
  std::map<std::string, std::pair<Eigen::Vector3d, int>> where;
  std::map<std::string, double> worst;
  for (const io::TargetRecord& t : project.targets) {
    const int s = project.FindScan(t.scan);
    if (!view.valid || s < 0 || !project.scans[s].registered) continue;
    const std::string key = t.name.empty() ? t.scan + "/" + std::to_string(&t - project.targets.data()) : t.name;
    auto& [sum, count] = where.try_emplace(key, Eigen::Vector3d::Zero(), 0).first->second;
    sum += project.scans[s].world_from_scan * t.center;
    ++count;
    const auto [it, first] = worst.try_emplace(key, t.residual_m);  // -1: no residual yet
    if (!first) it->second = std::max(it->second, t.residual_m);
  }
  for (const auto& [name, sum_count] : where) {
    const bool control = std::any_of(project.control.begin(), project.control.end(),
                                     [&](const io::ControlPoint& c) { return c.name == name; });
    const QColor colour = worst[name] > 0.01 ? QColor(210, 40, 40) : control ? QColor(40, 90, 220) : QColor(130, 130, 130);
    QPen pen(colour, 2);
    pen.setCosmetic(true);
    QPolygonF diamond({QPointF(0, -6), QPointF(6, 0), QPointF(0, 6), QPointF(-6, 0)});
    auto* mark = s->addPolygon(diamond, pen, QBrush(colour.lighter(150)));
    mark->setFlag(QGraphicsItem::ItemIgnoresTransformations);
    mark->setPos(view.Map(sum_count.first / sum_count.second));
    mark->setZValue(1);
    mark->setToolTip(tr("target %1: seen by %n scan(s)", "", sum_count.second).arg(QString::fromStdString(name)) +
                     (worst[name] >= 0 ? tr(", largest residual %1 mm").arg(worst[name] * 1000, 0, 'f', 1) : QString()));
    if (control) {
      auto* label = s->addSimpleText(QString::fromStdString(name));
      label->setFlag(QGraphicsItem::ItemIgnoresTransformations);
      label->setPos(view.Map(sum_count.first / sum_count.second));
      label->setTransform(QTransform::fromTranslate(7, 2));
      label->setBrush(colour);
    }
    ++targets_;
  }
  Fit();
}

QString NetworkPanel::ScanAt(QPoint view_pos) const {
  double best = node_radius_ + 4;
  QString out;
  for (std::size_t i = 0; i < pos_.size() && i < project_.scans.size(); ++i) {
    const QPointF d = QPointF(mapFromScene(pos_[i])) - QPointF(view_pos);
    const double r = std::hypot(d.x(), d.y());
    if (r <= best) best = r, out = QString::fromStdString(project_.scans[i].name);
  }
  return out;
}

std::vector<int> NetworkPanel::LinksNear(QPoint view_pos, double tolerance_px) const {
  std::vector<std::pair<double, int>> near;
  for (std::size_t k = 0; k < project_.links.size(); ++k) {
    const int a = project_.FindScan(project_.links[k].parent), b = project_.FindScan(project_.links[k].child);
    if (a < 0 || b < 0 || a >= static_cast<int>(pos_.size()) || b >= static_cast<int>(pos_.size())) continue;
    const double d = DistanceToSegment(QPointF(view_pos), QPointF(mapFromScene(pos_[a])), QPointF(mapFromScene(pos_[b])));
    if (d <= tolerance_px) near.emplace_back(d, static_cast<int>(k));
  }
  std::sort(near.begin(), near.end());
  std::vector<int> out;
  for (const auto& [d, k] : near) out.push_back(k);
  return out;
}

QString NetworkPanel::LinkToolTip(int k) const {
  const io::LinkRecord& l = project_.links[k];
  const QString kind = l.loop_check ? tr("loop check") : io::IsTreeLink(l) ? tr("link") : tr("attempt");
  QString tip = tr("%1 → %2 (%3): %4 — %5")
                    .arg(QString::fromStdString(l.child), QString::fromStdString(l.parent), kind,
                         io::LinkStatusName(l.status), QString::fromStdString(l.method));
  const bool measured = l.status != io::LinkStatus::kFailed || l.rms_m > 0.0 || l.overlap > 0.0;
  tip += tr("\n%1 matches (%2 geometric), %3 inliers, %4 consistent").arg(l.matches).arg(l.geometric_matches)
             .arg(l.ransac_inliers).arg(l.consistent);
  if (measured)
    tip += tr("\nRMS %1 mm, overlap %2 %, conflicts %3 %").arg(l.rms_m * 1000, 0, 'f', 1)
               .arg(l.overlap * 100, 0, 'f', 1).arg(l.conflict * 100, 0, 'f', 1);
  if (!l.picked.empty()) tip += tr("\nfrom %n picked point pair(s)", "", int(l.picked.size()));
  if (l.user_accepted) tip += tr("\naccepted by the user: kept by later registrations");
  if (l.user_rejected) tip += tr("\nrejected by the user");
  if (!l.reason.empty()) tip += "\n" + QString::fromStdString(l.reason);
  return tip;
}

QString NetworkPanel::ScanToolTip(const QString& name) const {
  const int i = project_.FindScan(name.toStdString());
  if (i < 0) return QString();
  const io::ProjectScan& s = project_.scans[i];
  QString tip = name + ": " + io::PoseStateName(io::ScanPoseState(s));
  if (io::RestsOnHandPlacement(project_)[i]) tip += tr("\nits pose rests on a hand placement");
  if (s.parent_override) tip += tr("\nparent set by hand: %1").arg(QString::fromStdString(*s.parent_override));
  if (!s.registered && !s.cluster.empty())
    tip += tr("\nin the cluster of %1: registered to its scans, not to the root; one link places the cluster")
               .arg(QString::fromStdString(s.cluster));
  // Why it is not registered — also when it kept its imported pose because the registration could not verify it.
  if ((!s.registered || s.imported_pose) && !s.unregistered_reason.empty())
    tip += "\n" + QString::fromStdString(s.unregistered_reason);
  if (s.consistency_m)
    tip += tr("\noverlaps agree to %1 mm (at the start pose %2 mm)")
               .arg(*s.consistency_m * 1000, 0, 'f', 3)
               .arg(s.start_consistency_m ? QString::number(*s.start_consistency_m * 1000, 'f', 3) : "—");
  return tip;
}

bool NetworkPanel::viewportEvent(QEvent* event) {
  if (event->type() == QEvent::ToolTip) {
    const auto* help = static_cast<QHelpEvent*>(event);
    QString tip = ScanToolTip(ScanAt(help->pos()));
    if (tip.isEmpty()) {
      const std::vector<int> links = LinksNear(help->pos());
      if (!links.empty()) tip = LinkToolTip(links.front());
      if (links.size() > 1) tip += tr("\n(%1 more link(s) here: right-click lists them)").arg(links.size() - 1);
    }
    if (tip.isEmpty()) QToolTip::hideText();
    else QToolTip::showText(help->globalPos(), tip, this);
    return true;
  }
  return ZoomView::viewportEvent(event);
}

void NetworkPanel::AddLinkActions(QMenu* menu, int k) {
  const QString parent = QString::fromStdString(project_.links[k].parent);
  const QString child = QString::fromStdString(project_.links[k].child);
  menu->addAction(tr("Accept link %1 → %2").arg(child, parent), this,
                  [this, parent, child] { emit LinkDecisionRequested(parent, child, true, false); });
  menu->addAction(tr("Reject link %1 → %2").arg(child, parent), this,
                  [this, parent, child] { emit LinkDecisionRequested(parent, child, false, true); });
  menu->addAction(tr("Clear decision"), this,
                  [this, parent, child] { emit LinkDecisionRequested(parent, child, false, false); });
}

void NetworkPanel::contextMenuEvent(QContextMenuEvent* event) {
  QMenu menu(this);
  const QString child = ScanAt(event->pos());
  if (!child.isEmpty()) {
    const int c = project_.FindScan(child.toStdString());
    std::string current;
    for (const io::LinkRecord& l : project_.links)
      if (io::IsTreeLink(l) && l.child == child.toStdString()) current = l.parent;
    // Candidates by matches with the child (the last registration's confusion matrix), most first.
    const Eigen::MatrixXi* confusion = project_.CurrentConfusion();
    std::vector<std::pair<int, int>> candidates;  // (-matches, scan)
    for (int p = 0; p < static_cast<int>(project_.scans.size()); ++p)
      if (p != c) candidates.emplace_back(confusion ? -std::max((*confusion)(p, c), (*confusion)(c, p)) : 0, p);
    std::stable_sort(candidates.begin(), candidates.end());
    QMenu* parent_menu = menu.addMenu(tr("Register %1 to").arg(child));
    for (const auto& [neg, p] : candidates) {
      const io::ProjectScan& s = project_.scans[p];
      QString text = QString::fromStdString(s.name);
      if (confusion && neg == -kSkippedPair) text += tr("  (not matched)");
      else if (confusion) text += tr("  (%n match(es))", "", -neg);
      if (s.name == current) text += tr("  — current parent");
      if (!s.registered) text += s.unverified ? tr("  — not verified") : tr("  — not registered");
      const QString name = QString::fromStdString(s.name);
      parent_menu->addAction(text, this, [this, child, name] { emit ParentOverrideRequested(child, name); });
    }
    QAction* clear = menu.addAction(tr("Clear parent override"), this,
                                    [this, child] { emit ParentOverrideRequested(child, QString()); });
    clear->setEnabled(project_.scans[c].parent_override.has_value());
  } else {
    const std::vector<int> links = LinksNear(event->pos());
    if (links.empty()) return;
    if (links.size() == 1) {
      AddLinkActions(&menu, links.front());
    } else {  // several links run close together here: one submenu each
      for (int k : links) {
        const io::LinkRecord& l = project_.links[k];
        QMenu* sub = menu.addMenu(QString("%1 → %2 (%3%4)")
                                      .arg(QString::fromStdString(l.child), QString::fromStdString(l.parent),
                                           io::LinkStatusName(l.status), l.loop_check ? tr(", loop check") : ""));
        AddLinkActions(sub, k);
      }
    }
  }
  menu.exec(event->globalPos());
}

}  // namespace scanreg::ui
