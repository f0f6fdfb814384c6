#pragma once
// The acoustic acknowledgement of on_converged (thesis Sect. 2.3.1 and App. A.3: the tutor has
// let go of the robot and cannot feel the transition, so the system beeps). A 0.15 s two-tone
// chime generated at start-up as a WAV file and played with Qt Multimedia's QSoundEffect; where
// Qt Multimedia is missing, the platform's beep.
#include <QObject>
#include <QTemporaryFile>
#include <memory>

class QSoundEffect;

namespace flexirob::ui {

class ConvergedChime : public QObject {
  Q_OBJECT

 public:
  explicit ConvergedChime(QObject* parent = nullptr);
  ~ConvergedChime() override;
  void play();
  /// True when the chime is a sound effect (Qt Multimedia), false for the platform beep.
  bool usesSoundEffect() const;

 private:
  QTemporaryFile wav_;
  QSoundEffect* effect_ = nullptr;
};

}  // namespace flexirob::ui
