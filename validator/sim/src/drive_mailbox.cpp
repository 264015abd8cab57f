#include "drive_mailbox.hpp"

#include <algorithm>
#include <array>

#include "ncservo/base/little_endian.hpp"
#include "ncservo/model/axis_model.hpp"
#include "ncservo/model/mailbox_tracker.hpp"
#include "ncservo/sim/models.hpp"
#include "ncservo/wire/diagnosis_texts.hpp"
#include "ncservo/wire/ecat_wire.hpp"

namespace ncservo::sim {
namespace {

constexpr std::size_t kSdoBody = ecat::kSdoDataAt + ecat::kSdoDataSize;  // command to data
constexpr std::uint16_t kGeneralError = 0x1000;                          // ERH-002's wrong code
constexpr std::uint16_t kFollowingError = 0x8611;                        // MBX-001's emergency
constexpr std::uint32_t kAbortNoObject = 0x06020000;
// SDO command bytes: the command specifier in bits 7..5.
constexpr std::uint8_t command(std::uint8_t specifier) {
  return static_cast<std::uint8_t>(specifier << ecat::kSdoSpecifierShift);
}
constexpr std::uint8_t kSdoUploadRequest = command(ecat::kSdoInitiateUploadRequest);
constexpr std::uint8_t kSdoUploadAnswer = command(ecat::kSdoInitiateUploadResponse);
constexpr std::uint8_t kSdoDownloadAnswer = command(ecat::kSdoInitiateDownloadResponse);
constexpr std::uint8_t kSdoAbortCommand = command(ecat::kSdoAbort);

// The error number of the drive maker's table (diag::kErrorNumbers) that goes with each error
// code the drive's cause bits carry (kSewCauses), in its emergencies and 1003h entries.
struct CodeNumber {
  std::uint16_t code;
  std::uint8_t number;
};
constexpr std::array<CodeNumber, 13> kCodeNumbers{{
    {0x2300, 2},   // output current too high
    {0x3100, 1},   // input voltage too high
    {0x4200, 12},  // overtemperature
    {0x6010, 0},   // watchdog reset
    {0x6100, 25},  // internal software error
    {0x6320, 22},  // rated current must be set
    {0x7305, 7},   // sensor 1 electrical fault
    {0x7306, 8},   // sensor 2 electrical fault
    {0x7600, 16},  // nonvolatile memory damaged
    {0x8100, 4},   // error at fieldbus
    {0x8130, 6},   // node guarding request too late
    {0x8400, 30},  // slippage error too large
    {0x8611, 13},  // following error window and time out exceeded
}};
std::uint8_t numberOf(std::uint16_t code) {
  for (const CodeNumber& row : kCodeNumbers) {
    if (row.code == code) return row.number;
  }
  return 25;  // internal software error: a code the drive has no number for
}
std::vector<std::uint8_t> coeMessage(std::uint8_t counter, std::uint8_t service,
                                     const std::uint8_t* body, std::size_t size) {
  std::vector<std::uint8_t> message(kMailboxBytes, 0);
  storeLe(&message[ecat::kMailboxLengthAt], ecat::kCoeHeaderSize + size, 2);
  message[ecat::kMailboxTypeAt] =
      static_cast<std::uint8_t>(ecat::kMailboxTypeCoe | counter << ecat::kMailboxCounterShift);
  storeLe(&message[ecat::kMailboxHeaderSize], std::uint32_t{service} << ecat::kCoeServiceShift, 2);
  std::copy_n(body, size, &message[ecat::kMailboxHeaderSize + ecat::kCoeHeaderSize]);
  return message;
}
std::array<std::uint8_t, kSdoBody> sdoBody(std::uint8_t command, std::uint16_t index,
                                           std::uint8_t subindex, std::uint32_t data) {
  std::array<std::uint8_t, kSdoBody> body{};
  body[ecat::kSdoCommandAt] = command;
  storeLe(&body[ecat::kSdoIndexAt], index, 2);
  body[ecat::kSdoSubindexAt] = subindex;
  storeLe(&body[ecat::kSdoDataAt], data, 4);
  return body;
}
// An expedited transfer of `size` bytes: bits 3..2 the bytes unused of 4, size indicated.
std::uint8_t expedited(std::uint8_t command, std::size_t size) {
  return static_cast<std::uint8_t>(command | ecat::kSdoExpedited | ecat::kSdoSizeIndicated |
                                   (ecat::kSdoDataSize - size) << ecat::kSdoUnusedBytesShift);
}
std::uint8_t nextCounter(std::uint8_t& counter) {  // 1..7 in turn
  counter = static_cast<std::uint8_t>(counter % 7 + 1);
  return counter;
}

}  // namespace

// --- the drive ---

void DriveMailbox::quirk(MailboxQuirk quirk) {
  switch (quirk) {
    case MailboxQuirk::SilentFault:
      silent_next_ = true;
      break;
    case MailboxQuirk::WrongHistoryCode:
      wrong_code_next_ = true;
      break;
    case MailboxQuirk::LoseHistory:
      history_.clear();
      break;
    case MailboxQuirk::EmergencyWithoutFault:
    case MailboxQuirk::ErrorResetNow:
      pending_.push_back(quirk);  // sent at the next step, which has the slave
      break;
  }
}

void DriveMailbox::send(Esc& esc, std::uint8_t service, const std::uint8_t* body, std::size_t size,
                        DriveSaid said) {
  said.station = esc.station();
  esc.mailbox_answers.push_back({coeMessage(nextCounter(counter_), service, body, size), said});
}

void DriveMailbox::emergency(Esc& esc, std::uint16_t code, std::uint8_t error_register,
                             std::uint8_t number) {
  std::array<std::uint8_t, ecat::kEmcySize> body{};
  storeLe(&body[ecat::kEmcyCodeAt], code, 2);
  body[ecat::kEmcyRegisterAt] = error_register;
  body[ecat::kEmcyDataAt] = code == diag::kErrorReset ? 0 : number;
  DriveSaid said;
  said.kind = driveMessageKindName(DriveMessage::Kind::Emergency);
  said.code = code;
  said.error_register = error_register;
  send(esc, ecat::kCoeServiceEmergency, body.data(), body.size(), said);
}

void DriveMailbox::step(std::uint32_t sew, Esc& esc) {
  for (const MailboxQuirk quirk : pending_) {
    if (quirk == MailboxQuirk::ErrorResetNow) {
      emergency(esc, diag::kErrorReset, 0, 0);
    } else {
      emergency(esc, kFollowingError, diag::errorRegisterFor(kFollowingError),
                numberOf(kFollowingError));
    }
  }
  pending_.clear();
  const std::uint32_t rose = sew & ~sew_ & kSewCauseMask;
  for (const SewCause& cause : kSewCauses) {
    if (rose == 0) break;  // most cycles: nothing rose
    if ((rose & cause.mask) == 0) continue;
    const std::uint16_t code = wrong_code_next_ ? kGeneralError : cause.canopen;
    wrong_code_next_ = false;
    error_register_ = diag::errorRegisterFor(cause.canopen);
    last_code_ = cause.canopen;
    history_.push_front(std::uint32_t{numberOf(cause.canopen)} << 24 |
                        std::uint32_t{error_register_} << 16 | code);
    if (history_.size() > diag::kErrorFieldEntries) history_.pop_back();
    if (silent_next_) continue;
    emergency(esc, cause.canopen, error_register_, numberOf(cause.canopen));
  }
  silent_next_ = silent_next_ && rose == 0;
  if ((sew_ & bits::kServoErrors) != 0 && (sew & bits::kServoErrors) == 0) {
    error_register_ = 0;
    emergency(esc, diag::kErrorReset, 0, 0);
  }
  sew_ = sew;
  for (const std::vector<std::uint8_t>& request : esc.mailbox_written) answer(esc, request);
  esc.mailbox_written.clear();
}

void DriveMailbox::sdo(Esc& esc, std::uint8_t service, std::uint8_t command,
                       DriveMessage::Kind kind, std::uint16_t index, std::uint8_t subindex,
                       std::uint32_t data) {
  const auto body = sdoBody(command, index, subindex, data);
  DriveSaid said;
  said.kind = driveMessageKindName(kind);
  said.index = index;
  said.subindex = subindex;
  if (kind == DriveMessage::Kind::SdoAbort) {
    said.abort_code = data;
  } else {
    said.value = data;
  }
  send(esc, service, body.data(), body.size(), said);
}

void DriveMailbox::upload(Esc& esc, std::uint16_t index, std::uint8_t subindex, std::uint32_t value,
                          std::size_t size) {
  sdo(esc, ecat::kCoeServiceSdoResponse, expedited(kSdoUploadAnswer, size),
      DriveMessage::Kind::SdoUpload, index, subindex, value);
}

void DriveMailbox::abort(Esc& esc, std::uint16_t index, std::uint8_t subindex, std::uint32_t code) {
  // an abort, either side's, is an SDO request (ETG.1000.6)
  sdo(esc, ecat::kCoeServiceSdoRequest, kSdoAbortCommand, DriveMessage::Kind::SdoAbort, index,
      subindex, code);
}

void DriveMailbox::answer(Esc& esc, const std::vector<std::uint8_t>& request) {
  const std::size_t at = ecat::kMailboxHeaderSize + ecat::kCoeHeaderSize;
  if (request.size() < at + kSdoBody) return;
  const std::uint8_t specifier = request[at + ecat::kSdoCommandAt] >> ecat::kSdoSpecifierShift;
  const auto index = static_cast<std::uint16_t>(loadLe(&request[at + ecat::kSdoIndexAt], 2));
  const std::uint8_t subindex = request[at + ecat::kSdoSubindexAt];
  if (specifier == ecat::kSdoInitiateDownloadRequest) {
    if (index == diag::kPredefinedErrorField && subindex == 0 &&
        loadLe(&request[at + ecat::kSdoDataAt], 1) == 0) {
      history_.clear();
      sdo(esc, ecat::kCoeServiceSdoResponse, kSdoDownloadAnswer, DriveMessage::Kind::SdoDownload,
          index, subindex, 0);
    } else {
      abort(esc, index, subindex, kAbortNoObject);
    }
    return;
  }
  if (index == diag::kErrorRegister && subindex == 0) {
    upload(esc, index, subindex, error_register_, 1);
  } else if (index == diag::kPredefinedErrorField && subindex == 0) {
    upload(esc, index, subindex, static_cast<std::uint32_t>(history_.size()), 1);
  } else if (index == diag::kPredefinedErrorField && subindex <= diag::kErrorFieldEntries) {
    if (subindex > history_.size()) {
      abort(esc, index, subindex, diag::kAbortNoDataAvailable);
    } else {
      upload(esc, index, subindex, history_[subindex - 1u], 4);
    }
  } else if (index == diag::kLastErrorCode && subindex == 0) {
    upload(esc, index, subindex, last_code_, 2);
  } else {
    abort(esc, index, subindex, kAbortNoObject);
  }
}

// --- the NC ---

void NcMailbox::upload(std::uint16_t index, std::uint8_t subindex) {
  queue_.push_back({index, subindex});
}
void NcMailbox::faultSeen() {
  upload(diag::kErrorRegister, 0);
  upload(diag::kPredefinedErrorField, 0);
  upload(diag::kPredefinedErrorField, 1);
}

std::optional<std::vector<std::uint8_t>> NcMailbox::takeRequest() {
  if (open_ || queue_.empty()) return std::nullopt;
  const Request r = queue_.front();
  queue_.pop_front();
  open_ = true;
  const auto body = sdoBody(kSdoUploadRequest, r.index, r.subindex, 0);
  return coeMessage(nextCounter(counter_), ecat::kCoeServiceSdoRequest, body.data(), body.size());
}

void NcMailbox::answered(const std::vector<std::uint8_t>& message) {
  const std::size_t at = ecat::kMailboxHeaderSize;
  if (message.size() < at + ecat::kCoeHeaderSize) return;
  const auto service = static_cast<std::uint8_t>(loadLe(&message[at], 2) >> ecat::kCoeServiceShift);
  if (service == ecat::kCoeServiceSdoRequest || service == ecat::kCoeServiceSdoResponse) {
    open_ = false;
  }
}

}  // namespace ncservo::sim
