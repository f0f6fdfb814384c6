#pragma once
// The 3D view: an OpenSceneGraph viewer drawing into a QOpenGLWidget through an embedded
// graphics window (no window of OSG's own), rendering in paintGL. The mouse orbits (left
// button), pans (middle, or left with Shift) and zooms (right button, wheel) around the scene.
#include <QOpenGLWidget>
#include <osg/Node>
#include <osg/ref_ptr>
#include <functional>
#include <vector>

#include <Eigen/Core>
#include <osgGA/OrbitManipulator>
#include <osgViewer/GraphicsWindow>
#include <osgViewer/Viewer>

#include "render/camera.hpp"

namespace flexirob::ui {

/// Takes the left mouse button before the camera does (the mouse perturbation of the arm).
/// press() returns true to take the drag; move() and release() then follow until release.
class ViewMouseGrabber {
 public:
  virtual ~ViewMouseGrabber() = default;
  virtual bool press(const QPointF& position) = 0;
  virtual void move(const QPointF& position) = 0;
  virtual void release() = 0;
};

class OsgView : public QOpenGLWidget {
  Q_OBJECT

 public:
  explicit OsgView(QWidget* parent = nullptr);
  ~OsgView() override;

  /// The tree to draw (not owned; must outlive the view or be replaced first).
  void setSceneRoot(osg::Node* root);
  /// Makes `camera` the home view and moves there.
  void setHomeCamera(const render::CameraPose& camera);
  /// Back to the home view.
  void resetCamera();
  /// Where the eye is now and what it looks at (world frame).
  render::CameraPose currentCamera() const;
  /// Frames drawn so far (for tests and frame-rate figures).
  long framesDrawn() const { return frames_; }

  /// The nearest surface under widget position `position` that belongs to one of `bodies`:
  /// its index in `bodies` and the hit point [m, W]; -1 if none.
  int pick(const QPointF& position, const std::vector<osg::Node*>& bodies, Eigen::Vector3d& point_W);
  /// The ray through widget position `position`: origin (on the near plane) and unit direction [W].
  void ray(const QPointF& position, Eigen::Vector3d& origin_W, Eigen::Vector3d& direction_W) const;
  /// Unit vector from the eye towards the centre of the view [W].
  Eigen::Vector3d viewDirection() const;
  /// Null or a grabber that gets left-button drags first (not owned).
  void setMouseGrabber(ViewMouseGrabber* grabber) { grabber_ = grabber; }
  /// Null or the handler of Ctrl+left clicks (e.g. set a goal): such a click then neither grabs
  /// the arm nor moves the camera.
  void setControlClickHandler(std::function<void(const QPointF&)> handler) { control_click_ = std::move(handler); }

 protected:
  void initializeGL() override;
  void resizeGL(int width, int height) override;
  void paintGL() override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  void mouseDoubleClickEvent(QMouseEvent* event) override;
  void wheelEvent(QWheelEvent* event) override;

 private:
  osgGA::EventQueue* events() const { return window_->getEventQueue(); }
  int osgButton(const QMouseEvent* event) const;
  double scale() const { return devicePixelRatioF(); }

  osg::ref_ptr<osgViewer::Viewer> viewer_;
  osg::ref_ptr<osgViewer::GraphicsWindowEmbedded> window_;
  osg::ref_ptr<osgGA::OrbitManipulator> manipulator_;
  render::CameraPose home_;
  long frames_ = 0;
  ViewMouseGrabber* grabber_ = nullptr;
  bool grabbing_ = false;
  std::function<void(const QPointF&)> control_click_;
  bool control_clicking_ = false;  // swallow the moves and the release of a Ctrl+click
};

}  // namespace flexirob::ui
