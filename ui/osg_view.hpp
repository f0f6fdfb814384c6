#pragma once
// The 3D view: an OpenSceneGraph viewer drawing through an embedded graphics window (no window
// of OSG's own) into a framebuffer object of the view's own OpenGL context; the frame is read
// back and painted as an image. A QOpenGLWidget would make Qt compose the whole window through
// OpenGL on every frame; on a software renderer (llvmpipe under Xvfb) that composition cost as
// much as drawing the scene. The mouse orbits (left button), pans (middle, or left with Shift)
// and zooms (right button, wheel) around the scene.
#include <QImage>
#include <QWidget>
#include <osg/Node>
#include <osg/ref_ptr>
#include <functional>
#include <optional>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <osgGA/OrbitManipulator>
#include <osgViewer/GraphicsWindow>
#include <osgViewer/Viewer>

#include "render/camera.hpp"

class QOffscreenSurface;
class QOpenGLContext;
class QOpenGLFramebufferObject;

namespace flexirob::ui {

class AboveFloorManipulator;

/// Takes the left mouse button before the camera does (the mouse perturbation of the arm).
/// press() returns true to take the drag; move() and release() then follow until release.
class ViewMouseGrabber {
 public:
  virtual ~ViewMouseGrabber() = default;
  virtual bool press(const QPointF& position) = 0;
  virtual void move(const QPointF& position) = 0;
  virtual void release() = 0;
};

class OsgView : public QWidget {
  Q_OBJECT

 public:
  explicit OsgView(QWidget* parent = nullptr);
  ~OsgView() override;

  /// The tree to draw (not owned; must outlive the view or be replaced first).
  void setSceneRoot(osg::Node* root);
  /// Makes `camera` the home view and moves there.
  void setHomeCamera(const render::CameraPose& camera);
  /// The height [m] the eye is kept above while orbiting, panning and zooming (the table top a
  /// robot stands on: seen from below it the scene reads upside down), or none (a robot that
  /// hangs, a scene without a table). A move that would take the eye lower is not made.
  void setFloor(std::optional<double> floor_z);
  /// Back to the home view.
  void resetCamera();
  /// Where the eye is now and what it looks at (world frame).
  render::CameraPose currentCamera() const;
  /// Frames drawn so far (for tests and frame-rate figures).
  long framesDrawn() const { return frames_; }
  /// Asks for a new frame at the next paint (the scene, the camera or the arm changed). Other
  /// repaints, e.g. under a label laid over the view, show the last frame again.
  void requestFrame();
  /// Draws a frame now and returns it (empty where the platform has no OpenGL).
  QImage grabFramebuffer();
  /// False where no OpenGL context could be made (e.g. Qt's offscreen platform): nothing is drawn.
  bool canRender() const { return !gl_failed_; }

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
  void paintEvent(QPaintEvent* event) override;
  void resizeEvent(QResizeEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  void mouseDoubleClickEvent(QMouseEvent* event) override;
  void wheelEvent(QWheelEvent* event) override;

 private:
  osgGA::EventQueue* events() const { return window_->getEventQueue(); }
  int osgButton(const QMouseEvent* event) const;
  double scale() const { return devicePixelRatioF(); }
  QSize pixelSize() const;  ///< the view in device pixels, at least 1 x 1
  void updateProjection();
  bool makeContextCurrent();
  void renderFrame();

  osg::ref_ptr<osgViewer::Viewer> viewer_;
  osg::ref_ptr<osgViewer::GraphicsWindowEmbedded> window_;
  osg::ref_ptr<AboveFloorManipulator> manipulator_;
  render::CameraPose home_;
  long frames_ = 0;
  std::unique_ptr<QOpenGLContext> context_;
  std::unique_ptr<QOffscreenSurface> surface_;
  std::unique_ptr<QOpenGLFramebufferObject> framebuffer_;
  std::unique_ptr<QOpenGLFramebufferObject> resolved_;  // multisampling resolved, to read from
  QImage frame_;          // the last frame drawn, top row first
  bool frame_due_ = true;
  bool gl_failed_ = false;
  ViewMouseGrabber* grabber_ = nullptr;
  bool grabbing_ = false;
  std::function<void(const QPointF&)> control_click_;
  bool control_clicking_ = false;  // swallow the moves and the release of a Ctrl+click
};

}  // namespace flexirob::ui
