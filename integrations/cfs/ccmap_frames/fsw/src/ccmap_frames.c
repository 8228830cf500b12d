/* ccmap_frames: the shared frame slots (ccmap_frames.h has the contract). */
#include "ccmap_frames.h"

static CCMAP_FRAMES_Slot_t CCMAP_FRAMES_Slots[CCMAP_FRAMES_SLOTS]; /* 2 x 6.6 MB, .bss */
static uint32              CCMAP_FRAMES_NextSequence;

static bool CCMAP_FRAMES_Swap(uint32 Slot, uint32 From, uint32 To)
{
    uint32 Expected = From;
    return __atomic_compare_exchange_n(&CCMAP_FRAMES_Slots[Slot].State, &Expected, To, false, __ATOMIC_ACQ_REL,
                                       __ATOMIC_ACQUIRE);
}

int32 CCMAP_FRAMES_Init(void)
{
    uint32 i;
    for (i = 0; i < CCMAP_FRAMES_SLOTS; ++i)
    {
        __atomic_store_n(&CCMAP_FRAMES_Slots[i].State, (uint32)CCMAP_FRAMES_FREE, __ATOMIC_RELEASE);
    }
    CCMAP_FRAMES_NextSequence = 0;
    OS_printf("CCMAP_FRAMES Initialized: %u slots of %u points\n", (unsigned)CCMAP_FRAMES_SLOTS,
              (unsigned)CCMAP_FRAMES_MAX_POINTS);
    return CFE_SUCCESS;
}

CCMAP_FRAMES_Slot_t *CCMAP_FRAMES_Acquire(uint32 *Slot)
{
    uint32 i;
    for (i = 0; i < CCMAP_FRAMES_SLOTS; ++i)
    {
        if (CCMAP_FRAMES_Swap(i, CCMAP_FRAMES_FREE, CCMAP_FRAMES_FILLING))
        {
            *Slot = i;
            return &CCMAP_FRAMES_Slots[i];
        }
    }
    return NULL;
}

int32 CCMAP_FRAMES_Ready(uint32 Slot, uint32 *Sequence)
{
    uint32 Seq;
    if (Slot >= CCMAP_FRAMES_SLOTS || Sequence == NULL ||
        __atomic_load_n(&CCMAP_FRAMES_Slots[Slot].State, __ATOMIC_ACQUIRE) != CCMAP_FRAMES_FILLING)
    {
        return CFE_ES_BAD_ARGUMENT;
    }
    Seq = __atomic_add_fetch(&CCMAP_FRAMES_NextSequence, 1u, __ATOMIC_RELAXED);
    CCMAP_FRAMES_Slots[Slot].Sequence = Seq;
    if (!CCMAP_FRAMES_Swap(Slot, CCMAP_FRAMES_FILLING, CCMAP_FRAMES_READY))
    {
        return CFE_ES_BAD_ARGUMENT;
    }
    *Sequence = Seq;
    return CFE_SUCCESS;
}

const CCMAP_FRAMES_Slot_t *CCMAP_FRAMES_Take(uint32 Slot, uint32 Sequence)
{
    if (Slot >= CCMAP_FRAMES_SLOTS || !CCMAP_FRAMES_Swap(Slot, CCMAP_FRAMES_READY, CCMAP_FRAMES_BUSY))
    {
        return NULL;
    }
    if (CCMAP_FRAMES_Slots[Slot].Sequence != Sequence)
    {
        /* Not the frame the message names: leave it READY for its own message. */
        (void)CCMAP_FRAMES_Swap(Slot, CCMAP_FRAMES_BUSY, CCMAP_FRAMES_READY);
        return NULL;
    }
    return &CCMAP_FRAMES_Slots[Slot];
}

void CCMAP_FRAMES_Release(uint32 Slot)
{
    if (Slot < CCMAP_FRAMES_SLOTS)
    {
        __atomic_store_n(&CCMAP_FRAMES_Slots[Slot].State, (uint32)CCMAP_FRAMES_FREE, __ATOMIC_RELEASE);
    }
}
