#pragma once
// A menu of checkable actions, one per overlay layer (render/overlays.hpp), that shows and hides
// the layers of one render::Overlays. Wiring into the main window: create it with the world's
// overlays, add it to the menu bar (menuBar()->addMenu(menu)), and call update() on the view
// from the toggled() signal so the change shows at once.
#include <QMenu>

#include <array>

#include "render/overlays.hpp"

namespace flexirob::ui {

class OverlayMenu : public QMenu {
  Q_OBJECT

 public:
  /// `overlays` must outlive the menu. Every layer starts visible.
  explicit OverlayMenu(render::Overlays& overlays, QWidget* parent = nullptr);

  /// The action of one layer (checked = visible).
  QAction* action(render::OverlayLayer layer) const { return actions_[static_cast<std::size_t>(layer)]; }

 Q_SIGNALS:
  void toggled(render::OverlayLayer layer, bool visible);

 private:
  std::array<QAction*, render::kOverlayLayerCount> actions_{};
};

}  // namespace flexirob::ui
