/*
 * canfdi_startup.c — minimal Cortex-M (ARMv6-M / ARMv7-M) start-up for the
 * canfdi target images: the exception vector table and a Reset_Handler that
 * copies .data from flash, zeroes .bss and calls main().
 *
 * Shared by the Cortex-M4 and Cortex-M0+ builds: the 16 system entries of
 * the table have the same layout on both (entries a core lacks are reserved
 * and left at Default_Handler). No device interrupts are listed yet; a port
 * that uses a peripheral IRQ appends it to canfdi_vector_table.
 *
 * No C library call is made before main(): newlib is linked only so that a
 * stray heap or soft-float call links and is then reported by the target
 * guard (tests/target/fw_guard.sh), instead of failing obscurely.
 *
 * Memory: 64 bytes of flash for the table, no RAM.
 */
#include <stdint.h>

/* Provided by canfdi_cortexm.ld. Only their addresses are meaningful. */
extern uint32_t __data_load__;
extern uint32_t __data_start__;
extern uint32_t __data_end__;
extern uint32_t __bss_start__;
extern uint32_t __bss_end__;
extern uint32_t __stack_top__;

int main(void);
void Reset_Handler(void);
void Default_Handler(void);
void NMI_Handler(void) __attribute__((weak, alias("Default_Handler")));
void HardFault_Handler(void) __attribute__((weak, alias("Default_Handler")));
void MemManage_Handler(void) __attribute__((weak, alias("Default_Handler")));
void BusFault_Handler(void) __attribute__((weak, alias("Default_Handler")));
void UsageFault_Handler(void) __attribute__((weak, alias("Default_Handler")));
void SVC_Handler(void) __attribute__((weak, alias("Default_Handler")));
void DebugMon_Handler(void) __attribute__((weak, alias("Default_Handler")));
void PendSV_Handler(void) __attribute__((weak, alias("Default_Handler")));
void SysTick_Handler(void) __attribute__((weak, alias("Default_Handler")));

typedef void (*canfdi_vector_t)(void);

/* The initial stack pointer is an object address, the rest are handlers;
 * a struct keeps both types honest (no object-to-function pointer cast). */
struct canfdi_vector_table
{
  uint32_t *initial_sp;
  canfdi_vector_t handler[15];
};

const struct canfdi_vector_table canfdi_vector_table
    __attribute__((section(".isr_vector"), used)) = {
        &__stack_top__,
        {
            Reset_Handler,
            NMI_Handler,
            HardFault_Handler,
            MemManage_Handler,  /* reserved on ARMv6-M */
            BusFault_Handler,   /* reserved on ARMv6-M */
            UsageFault_Handler, /* reserved on ARMv6-M */
            Default_Handler,    /* reserved */
            Default_Handler,    /* reserved */
            Default_Handler,    /* reserved */
            Default_Handler,    /* reserved */
            SVC_Handler,
            DebugMon_Handler, /* reserved on ARMv6-M */
            Default_Handler,  /* reserved */
            PendSV_Handler,
            SysTick_Handler,
        },
};

void Reset_Handler(void)
{
  /* Word copies: the linker script aligns all four bounds to 4 bytes.
   * Addresses are compared as integers because the bounds are distinct
   * objects as far as C is concerned. */
  const uint32_t *src = &__data_load__;
  uint32_t *dst = &__data_start__;
  while ((uintptr_t)dst < (uintptr_t)&__data_end__)
  {
    *dst = *src;
    dst++;
    src++;
  }
  dst = &__bss_start__;
  while ((uintptr_t)dst < (uintptr_t)&__bss_end__)
  {
    *dst = 0U;
    dst++;
  }
  (void)main();
  /* Nothing to return to on bare metal: park the core. */
  for (;;)
  {
  }
}

/* Any unexpected exception parks here, where a debugger can see it. */
void Default_Handler(void)
{
  for (;;)
  {
  }
}
