#include "ui/converged_chime.hpp"

#include <QApplication>
#include <QDataStream>
#include <QDir>
#include <QUrl>
#include <algorithm>
#include <cmath>
#include <numbers>

#ifdef FLEXIROB_HAVE_QT_MULTIMEDIA
#include <QSoundEffect>
#endif

namespace flexirob::ui {
#ifdef FLEXIROB_HAVE_QT_MULTIMEDIA
namespace {

// 16-bit mono PCM: two short tones (880 Hz then 1320 Hz) with 10 ms fades against clicks.
QByteArray chimeWav() {
  constexpr int kRate = 22050;
  constexpr double kToneSeconds = 0.075;
  const int tone_samples = static_cast<int>(kToneSeconds * kRate);
  const int fade = kRate / 100;
  QByteArray pcm;
  QDataStream pcm_out(&pcm, QIODevice::WriteOnly);
  pcm_out.setByteOrder(QDataStream::LittleEndian);
  for (const double frequency : {880.0, 1320.0}) {
    for (int i = 0; i < tone_samples; ++i) {
      const double envelope = std::min({1.0, static_cast<double>(i) / fade, static_cast<double>(tone_samples - i) / fade});
      const double value = 0.35 * envelope * std::sin(2.0 * std::numbers::pi * frequency * i / kRate);
      pcm_out << static_cast<qint16>(std::lround(value * 32767.0));
    }
  }
  QByteArray wav;
  QDataStream out(&wav, QIODevice::WriteOnly);
  out.setByteOrder(QDataStream::LittleEndian);
  out.writeRawData("RIFF", 4);
  out << static_cast<quint32>(36 + pcm.size());
  out.writeRawData("WAVEfmt ", 8);
  out << static_cast<quint32>(16) << static_cast<quint16>(1) << static_cast<quint16>(1) << static_cast<quint32>(kRate)
      << static_cast<quint32>(kRate * 2) << static_cast<quint16>(2) << static_cast<quint16>(16);
  out.writeRawData("data", 4);
  out << static_cast<quint32>(pcm.size());
  out.writeRawData(pcm.constData(), static_cast<int>(pcm.size()));
  return wav;
}

}  // namespace
#endif

ConvergedChime::ConvergedChime(QObject* parent) : QObject(parent) {
#ifdef FLEXIROB_HAVE_QT_MULTIMEDIA
  wav_.setFileTemplate(QDir::tempPath() + QStringLiteral("/flexirob-chime-XXXXXX.wav"));
  if (wav_.open()) {
    wav_.write(chimeWav());
    wav_.flush();
    effect_ = new QSoundEffect(this);
    effect_->setSource(QUrl::fromLocalFile(wav_.fileName()));
    effect_->setVolume(0.8F);
  }
#endif
}

ConvergedChime::~ConvergedChime() = default;

bool ConvergedChime::usesSoundEffect() const { return effect_ != nullptr; }

void ConvergedChime::play() {
#ifdef FLEXIROB_HAVE_QT_MULTIMEDIA
  if (effect_ != nullptr) {
    effect_->play();
    return;
  }
#endif
  QApplication::beep();
}

}  // namespace flexirob::ui
