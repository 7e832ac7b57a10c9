/* Fuzz target: frame decode and E2E (port/src/frames.c on port/codec).
 * The input drives a bus: raw frames of any ID, flags, length and bytes;
 * well-formed E2E-protected input frames (sometimes corrupted); stale
 * polls; and output frames encoded from any values, NaN included.
 * Invariants: every result is one the API documents; accepted exactly
 * when E2E says so; an accepted input's value is the one sent; a clean
 * in-sequence frame is accepted; an output frame carries a correct CRC
 * and counter; an estimate frame marked valid holds finite, unclamped
 * values the estimator called valid, and a non-finite or clamped one with
 * a fix carries the fault bit (issue 11, classes 1 and 4). */
#include <math.h>

#include "frames.h"
#include "fuzz.h"
#include "hstpf_can.h"
#include "hstpf_frames.h"

static uint32_t pick_id(fuzz_in_t *in, uint8_t *flags)
{
    const uint8_t sel = fuzz_u8(in);
    switch (sel % 7u) {
    case 0:
        return HSTPF_FRAME_POSITION_ID;
    case 1:
        return HSTPF_FRAME_TRACTION_ID;
    case 6:
        return HSTPF_FRAME_CONSIST_ID;
    case 2:
        return hstpfd_tx_id(fuzz_u8(in) % HSTPFD_N_OUTPUTS);
    case 3:
        *flags |= HSTPFD_FRAME_EXT;
        return fuzz_u32(in) & 0x1FFFFFFFu;
    default:
        return fuzz_u16(in) & 0x7FFu;
    }
}

static void check_rx(const hstpfd_rx_t *r, const hstpfd_frame_t *f)
{
    FUZZ_CHECK(r->kind <= HSTPFD_RX_CONSIST, "kind %d", (int)r->kind);
    if (r->kind == HSTPFD_RX_POSITION || r->kind == HSTPFD_RX_TRACTION || r->kind == HSTPFD_RX_CONSIST) {
        FUZZ_CHECK(r->e2e <= HSTPF_E2E_COUNTER_JUMP, "e2e result %d", (int)r->e2e);
        FUZZ_CHECK(r->accepted == (hstpf_e2e_accepted(r->e2e) != 0), "accepted %d for %d", r->accepted, (int)r->e2e);
        FUZZ_CHECK(!r->valid || r->accepted, "valid but not accepted");
        FUZZ_CHECK(isfinite(r->value), "decoded value %g", r->value);
        FUZZ_CHECK(f->len == 8u || !r->accepted, "accepted with length %u", (unsigned)f->len);
    } else {
        FUZZ_CHECK(!r->accepted && !r->valid, "kind %d accepted", (int)r->kind);
    }
}

static void check_tx(const hstpfd_frame_t *f, unsigned i, const hstpfd_tx_values_t *v)
{
    const hstpf_frame_info_t *info = hstpf_frame_find(f->id);
    FUZZ_CHECK(info != NULL && f->id == hstpfd_tx_id(i) && f->len == info->length, "output %u id/len", i);
    FUZZ_CHECK(hstpf_e2e_frame_crc(info->data_id, f->data, f->len) == f->data[0], "output %u CRC", i);
    FUZZ_CHECK((f->data[1] & 0x0Fu) <= HSTPF_E2E_COUNTER_MAX, "output %u counter", i);
    if (i == 0u) {
        struct hstpf_can_est_state_t m;
        FUZZ_CHECK(hstpf_can_est_state_unpack(&m, f->data, f->len) == 0, "EstState unpack");
        {
            /* issue 11, classes 1 and 4 (fixed): nothing non-finite or clamped
             * leaves marked valid, and such a value with a fix is a fault */
            const int in_range = isfinite(v->position_m) && isfinite(v->speed_mps) &&
                                 fabs(v->position_m) <= 21474836.47 && fabs(v->speed_mps) <= 327.67;
            FUZZ_CHECK(m.est_valid != HSTPF_CAN_EST_STATE_EST_VALID_VALID_CHOICE || (in_range && v->valid),
                       "EstValid=1 with position %g m, speed %g m/s, valid %u", v->position_m, v->speed_mps,
                       (unsigned)v->valid);
            FUZZ_CHECK(!v->have_fix || in_range || m.est_fault == HSTPF_CAN_EST_STATE_EST_FAULT_CLAMPED_CHOICE,
                       "position %g m, speed %g m/s sent without EstFault", v->position_m, v->speed_mps);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_in_t in;
    hstpfd_rx_state_t rx;
    hstpfd_tx_state_t tx;
    hstpf_e2e_tx_t send[2];
    uint8_t clean[2] = {0, 0}; /* stream untouched since our last accepted frame */
    uint32_t now = 0, timeout[2];
    unsigned steps;
    uint8_t max_delta;

    fuzz_in(&in, data, size);
    max_delta = (uint8_t)(1u + fuzz_u8(&in) % 13u);
    timeout[0] = 1u + fuzz_u16(&in);
    timeout[1] = 1u + fuzz_u16(&in);
    FUZZ_CHECK(hstpfd_rx_init(&rx, max_delta, timeout[0], timeout[1]) == 0, "rx init");
    FUZZ_CHECK(hstpfd_rx_init(&rx, 0, timeout[0], timeout[1]) != 0, "max_delta 0 accepted");
    FUZZ_CHECK(hstpfd_rx_init(&rx, max_delta, timeout[0], timeout[1]) == 0, "rx init again");
    hstpfd_tx_init(&tx);
    (void)hstpf_e2e_tx_init(&send[0], HSTPF_FRAME_POSITION_DATA_ID);
    (void)hstpf_e2e_tx_init(&send[1], HSTPF_FRAME_TRACTION_DATA_ID);

    for (steps = 0; steps < 4096 && in.i < in.n; ++steps) {
        const uint8_t op = fuzz_u8(&in);
        hstpfd_frame_t f;
        hstpfd_rx_t r;
        memset(&f, 0, sizeof f);
        now += fuzz_u8(&in) * (op & 0x80u ? 1000u : 1u);
        switch (op % 4u) {
        case 0: { /* any frame */
            unsigned k;
            f.flags = (uint8_t)(fuzz_u8(&in) & 0x0Fu);
            f.id = pick_id(&in, &f.flags);
            f.len = (uint8_t)(fuzz_u8(&in) % (HSTPFD_FRAME_MAX_DATA + 1u));
            for (k = 0; k < f.len; ++k) {
                f.data[k] = fuzz_u8(&in);
            }
            hstpfd_rx_decode(&rx, &f, now, &r);
            check_rx(&r, &f);
            if (r.kind == HSTPFD_RX_POSITION || r.kind == HSTPFD_RX_TRACTION) {
                clean[r.kind] = 0;
            }
            break;
        }
        case 1: { /* a well-formed input frame, sometimes corrupted */
            const unsigned w = fuzz_u8(&in) & 1u;
            const uint8_t corrupt = fuzz_u8(&in);
            const uint8_t was_clean = clean[w];
            double sent;
            if (w == 0u) {
                struct hstpf_can_position_t m;
                (void)hstpf_can_position_init(&m);
                m.pos_valid = (uint8_t)(fuzz_u8(&in) & 1u);
                m.position = hstpf_frames_position_position_raw(fuzz_double(&in, -1e8, 1e8));
                sent = hstpf_can_position_position_decode(m.position);
                (void)hstpf_can_position_pack(f.data, &m, 8u);
                f.id = HSTPF_FRAME_POSITION_ID;
            } else {
                struct hstpf_can_traction_t m;
                (void)hstpf_can_traction_init(&m);
                m.tract_valid = (uint8_t)(fuzz_u8(&in) & 1u);
                m.tract_force = hstpf_frames_traction_tract_force_raw(fuzz_double(&in, -1e4, 1e4));
                sent = hstpf_can_traction_tract_force_decode(m.tract_force);
                (void)hstpf_can_traction_pack(f.data, &m, 8u);
                f.id = HSTPF_FRAME_TRACTION_ID;
            }
            f.len = 8u;
            (void)hstpf_e2e_protect(&send[w], f.data, f.len);
            if (corrupt & 1u) {
                f.data[(corrupt >> 1) % 8u] ^= (uint8_t)(1u << ((corrupt >> 4) % 8u));
            }
            hstpfd_rx_decode(&rx, &f, now, &r);
            check_rx(&r, &f);
            if (!(corrupt & 1u)) {
                /* CRC-8 catches every single-bit error; a clean frame next in
                 * sequence on an untouched stream is accepted with its value */
                FUZZ_CHECK(!was_clean || r.accepted, "clean in-sequence frame refused: %s",
                           hstpf_e2e_result_name(r.e2e));
                if (r.accepted) {
                    FUZZ_CHECK(r.value == sent, "sent %.17g, decoded %.17g", sent, r.value);
                }
            } else {
                FUZZ_CHECK(r.e2e == HSTPF_E2E_BAD_CRC, "a single-bit error passed: %s", hstpf_e2e_result_name(r.e2e));
            }
            clean[w] = (uint8_t)(r.accepted && !(corrupt & 1u));
            break;
        }
        case 2: /* stale supervision */
            hstpfd_rx_poll(&rx, now);
            clean[0] = clean[1] = 0; /* after a stale period the next frame resyncs */
            break;
        default: { /* an output frame from any values */
            hstpfd_tx_values_t v;
            const unsigned i = fuzz_u8(&in) % HSTPFD_N_OUTPUTS;
            memset(&v, 0, sizeof v);
            {
                const uint8_t hf = fuzz_u8(&in);
                v.have_fix = (uint8_t)(hf & 1u);
                v.valid = (uint8_t)!(hf & 2u); /* mostly claimed valid: the frame must not believe it */
            }
            v.position_m = fuzz_double(&in, -3e7, 3e7);
            v.speed_mps = fuzz_double(&in, -400.0, 400.0);
            v.status = (hstpf_status_t)(fuzz_u8(&in) % 4u);
            v.declared_row = (int)(fuzz_u8(&in) % 20u) - 2;
            v.declared_q = fuzz_double(&in, 0.0, 1.0);
            v.leader_row = (int)(fuzz_u8(&in) % 20u) - 2;
            v.leader_q = fuzz_double(&in, 0.0, 1.0);
            v.theta[0] = fuzz_double(&in, 0.0, 70.0);
            v.theta[1] = fuzz_double(&in, 0.0, 0.1);
            v.theta[2] = fuzz_double(&in, 0.0, 0.002);
            v.pos_stale = fuzz_u8(&in);
            v.trac_stale = fuzz_u8(&in);
            v.bad_crc = fuzz_u32(&in);
            v.repeated = fuzz_u32(&in);
            v.jump = fuzz_u32(&in);
            v.wrong_length = fuzz_u32(&in);
            v.stale_events = fuzz_u32(&in);
            v.unknown_id = fuzz_u32(&in);
            v.error_frames = fuzz_u32(&in);
            v.degeneracy = fuzz_u32(&in);
            FUZZ_CHECK(hstpfd_tx_encode(&tx, i, &v, &f) == 0, "output %u not encoded", i);
            check_tx(&f, i, &v);
            break;
        }
        }
    }
    return 0;
}
