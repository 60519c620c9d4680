#include "load/operation_generator.hpp"

#include <algorithm>
#include <cstring>

#include "codec/function_code.hpp"
#include "codec/mbap.hpp"
#include "codec/pdu.hpp"

namespace mbstorm::load {
namespace {

constexpr std::size_t kHeader = codec::limits::kMbapHeader;

std::size_t max_pdu_size(const Operation& op) noexcept {
    return codec::request_pdu_size(op.function, op.quantity, op.write_quantity);
}

}  // namespace

std::size_t max_request_size(const Operation& op) noexcept {
    return kHeader + max_pdu_size(op);
}

std::size_t max_request_size(const std::vector<Operation>& operations) noexcept {
    std::size_t size = kHeader + 1;
    for (const Operation& op : operations) size = std::max(size, max_request_size(op));
    return size;
}

AddressPicker::AddressPicker(const Operation& op) noexcept
    : mode_(op.address_mode), first_(op.first_address) {
    positions_ = static_cast<std::uint32_t>(last_start_address(op)) - op.first_address + 1;
    stride_ = address_span(op);
    // Whole blocks only, so that a shard's requests tile the range like everyone else's.
    if (mode_ == AddressMode::Sequential) {
        const std::uint32_t blocks = (positions_ + stride_ - 1) / stride_;
        cursor_ = (op.start_offset / stride_ % blocks) * stride_;
    }
    if (mode_ == AddressMode::Zipf) zipf_ = ZipfSampler(positions_, op.zipf_exponent);
}

std::uint16_t AddressPicker::draw(Rng& rng) noexcept {
    std::uint32_t offset = 0;
    switch (mode_) {
        case AddressMode::Sequential:
            return next(rng);
        case AddressMode::Uniform:
            offset = rng.below(positions_);
            break;
        case AddressMode::Zipf:
            offset = zipf_.sample(rng) - 1;
            break;
    }
    return static_cast<std::uint16_t>(first_ + offset);
}

std::uint16_t ValuePicker::next(Rng& rng) noexcept {
    if (spec_ == nullptr) return 0;
    switch (spec_->mode) {
        case ValueMode::Constant:
            return spec_->value;
        case ValueMode::Counter: {
            const std::uint16_t v = counter_;
            counter_ = static_cast<std::uint16_t>(counter_ + spec_->step);
            return v;
        }
        case ValueMode::Random:
            return static_cast<std::uint16_t>(rng.next() >> 48);
        case ValueMode::Pattern: {
            if (spec_->pattern.empty()) return 0;
            const std::uint16_t v = spec_->pattern[pattern_index_];
            if (++pattern_index_ == spec_->pattern.size()) pattern_index_ = 0;
            return v;
        }
    }
    return 0;
}

bool ValuePicker::next_bit(Rng& rng) noexcept {
    const std::uint16_t v = next(rng);
    if (spec_ == nullptr) return false;
    return (spec_->mode == ValueMode::Constant || spec_->mode == ValueMode::Pattern) ? v != 0
                                                                                     : (v & 1) != 0;
}

OperationGenerator::OperationGenerator(const std::vector<Operation>& operations, std::uint64_t seed)
    : operations_(operations), rng_(seed) {
    cumulative_weight_.reserve(operations.size());
    state_.reserve(operations.size());
    std::uint64_t total = 0;
    for (const Operation& op : operations) {
        total += op.weight;
        cumulative_weight_.push_back(total);
        OpState st;
        st.address = AddressPicker(op);
        st.values = ValuePicker(op.values);
        st.max_size = max_request_size(op);
        const codec::FunctionInfo* f = codec::function_info(op.function);
        st.read = f != nullptr && f->request == codec::RequestShape::AddressQuantity;
        if (st.read) {
            codec::write_mbap_header(st.read_frame.data(), 0, op.unit_id, 5);
            codec::encode_read_request(op.function, 0, op.quantity,
                                       codec::MutableBytes(st.read_frame).subspan(kHeader));
            st.read_info.op_index = static_cast<std::uint16_t>(state_.size());
            st.read_info.function = op.function;
            st.read_info.unit_id = op.unit_id;
            st.read_info.quantity = op.quantity;
            const bool bits = f->response == codec::ResponseShape::Bits;
            const bool registers = f->response == codec::ResponseShape::Registers;
            const std::size_t bytes = bits ? (op.quantity + 7u) / 8u : 2u * op.quantity;
            // A validated plan's reads all fit one answer; anything else gets no fast check.
            if ((bits || registers) && bytes != 0 && bytes <= 2u * codec::limits::kMaxReadRegisters)
                st.read_info.answer_bytes = static_cast<std::uint8_t>(bytes);
        }
        state_.push_back(st);
    }
    single_read_ = state_.size() == 1 && state_.front().read;
}

std::uint16_t OperationGenerator::pick_operation() noexcept {
    if (cumulative_weight_.size() <= 1) return 0;
    const std::uint64_t total = cumulative_weight_.back();
    // 64x64->128 multiply-shift: uniform in [0, total) for any 64-bit total.
    const auto r =
        static_cast<std::uint64_t>((static_cast<unsigned __int128>(rng_.next()) * total) >> 64);
    const auto it = std::upper_bound(cumulative_weight_.begin(), cumulative_weight_.end(), r);
    return static_cast<std::uint16_t>(it - cumulative_weight_.begin());
}

std::size_t OperationGenerator::next_of_many(std::uint16_t transaction_id, codec::MutableBytes out,
                                             RequestInfo& info) noexcept {
    if (operations_.empty()) return 0;
    const std::uint16_t op_index = cumulative_weight_.size() == 1 ? 0 : pick_operation();
    OpState& st = state_[op_index];
    if (st.read) return write_read(st, transaction_id, out, info);
    return encode(op_index, transaction_id, out, info);
}

std::size_t OperationGenerator::encode(std::uint16_t op_index, std::uint16_t transaction_id,
                                       codec::MutableBytes out, RequestInfo& info) noexcept {
    const Operation& op = operations_[op_index];
    OpState& st = state_[op_index];
    if (out.size() < st.max_size) return 0;

    info = RequestInfo{};
    info.op_index = op_index;
    info.function = op.function;
    info.unit_id = op.unit_id;

    codec::MutableBytes pdu_out = out.subspan(kHeader);
    codec::EncodeResult pdu{};
    codec::Request req;
    req.function = op.function;
    // validate_plan() admitted only generatable functions, so the descriptor exists.
    const codec::RequestShape shape = codec::function_info(op.function)->request;
    switch (shape) {
        case codec::RequestShape::AddressQuantity:
            info.address = st.address.next(rng_);
            info.quantity = op.quantity;
            pdu = codec::encode_read_request(op.function, info.address, info.quantity, pdu_out);
            break;
        case codec::RequestShape::SingleCoil:
            req.address = info.address = st.address.next(rng_);
            req.value = info.value =
                st.values.next_bit(rng_) ? codec::limits::kCoilOn : codec::limits::kCoilOff;
            break;
        case codec::RequestShape::SingleRegister:
            req.address = info.address = st.address.next(rng_);
            req.value = info.value = st.values.next(rng_);
            break;
        case codec::RequestShape::SubFunction:
            req.sub_function = info.sub_function = op.sub_function;
            codec::store_be16(payload_.data(), st.values.next(rng_));
            req.payload = codec::Bytes(payload_.data(), 2);
            break;
        case codec::RequestShape::MultipleCoils: {
            req.address = info.address = st.address.next(rng_);
            req.quantity = info.quantity = op.quantity;
            const std::size_t bytes = (op.quantity + 7u) / 8u;
            std::fill_n(payload_.begin(), bytes, std::uint8_t{0});
            for (std::uint16_t i = 0; i < op.quantity; ++i) {
                if (st.values.next_bit(rng_)) payload_[i / 8] |= std::uint8_t(1u << (i % 8));
            }
            req.payload = codec::Bytes(payload_.data(), bytes);
            break;
        }
        case codec::RequestShape::MultipleRegisters:
            req.address = info.address = st.address.next(rng_);
            req.quantity = info.quantity = op.quantity;
            for (std::uint16_t i = 0; i < op.quantity; ++i) {
                codec::store_be16(payload_.data() + 2 * i, st.values.next(rng_));
            }
            req.payload = codec::Bytes(payload_.data(), 2u * op.quantity);
            break;
        case codec::RequestShape::MaskWrite:
            req.address = info.address = st.address.next(rng_);
            req.and_mask = info.and_mask = op.and_mask;
            req.or_mask = info.value = st.values.next(rng_);
            break;
        case codec::RequestShape::ReadWriteRegisters:
            req.address = info.address = st.address.next(rng_);
            req.quantity = info.quantity = op.quantity;
            req.write_address = info.address;
            req.write_quantity = op.write_quantity;
            for (std::uint16_t i = 0; i < op.write_quantity; ++i) {
                codec::store_be16(payload_.data() + 2 * i, st.values.next(rng_));
            }
            req.payload = codec::Bytes(payload_.data(), 2u * op.write_quantity);
            break;
        case codec::RequestShape::FifoPointer:
            req.address = info.address = st.address.next(rng_);
            break;
        case codec::RequestShape::MeiTransport:
            req.mei_type = codec::kMeiReadDeviceId;
            req.device_id_code = op.device_id_code;
            req.object_id = 0;
            break;
        case codec::RequestShape::FunctionOnly:
            break;
        case codec::RequestShape::FileRecords:
            return 0;  // not generatable: validate_plan() refuses it
    }
    // Reads took the fast path above; every other shape goes through the checked encoder.
    if (shape != codec::RequestShape::AddressQuantity) pdu = codec::encode_request(req, pdu_out);
    if (!pdu.ok()) return 0;
    const codec::EncodeResult adu = codec::encode_tcp_frame(
        transaction_id, op.unit_id, codec::Bytes(pdu_out.data(), pdu.size), out);
    return adu.ok() ? adu.size : 0;
}

}  // namespace mbstorm::load
