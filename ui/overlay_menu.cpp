#include "ui/overlay_menu.hpp"

#include <QAction>

namespace flexirob::ui {

OverlayMenu::OverlayMenu(render::Overlays& overlays, QWidget* parent) : QMenu(QStringLiteral("&Overlays"), parent) {
  for (render::OverlayLayer layer : render::kAllOverlayLayers) {
    QAction* action = addAction(QString::fromUtf8(render::overlayLayerTitle(layer)));
    action->setCheckable(true);
    action->setChecked(overlays.visible(layer));
    action->setObjectName(QStringLiteral("overlay_") + QString::fromUtf8(render::overlayLayerName(layer)));
    connect(action, &QAction::toggled, this, [this, &overlays, layer](bool visible) {
      overlays.setVisible(layer, visible);
      Q_EMIT toggled(layer, visible);
    });
    actions_[static_cast<std::size_t>(layer)] = action;
  }
}

}  // namespace flexirob::ui
