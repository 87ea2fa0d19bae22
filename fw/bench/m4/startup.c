/* startup.c - minimal Cortex-M4F start-up for the qemu benchmark: vector table, FPU on, .data/.bss. */
#include <stdint.h>

extern uint32_t _stack_top;
extern uint32_t _data_load;
extern uint32_t _data_start;
extern uint32_t _data_end;
extern uint32_t _bss_start;
extern uint32_t _bss_end;

int main(void);
void Reset_Handler(void);
void Default_Handler(void);
void bench_exit(int code);

void Default_Handler(void)
{
    bench_exit(3);
}

void Reset_Handler(void)
{
    volatile uint32_t *const cpacr = (volatile uint32_t *)0xE000ED88U;
    const uint32_t *src = &_data_load;
    uint32_t *dst = &_data_start;
    *cpacr |= (0xFU << 20); /* CP10, CP11 full access: the FPU */
    __asm volatile("dsb\n\tisb" ::: "memory");
    while (dst < &_data_end)
    {
        *dst++ = *src++;
    }
    for (dst = &_bss_start; dst < &_bss_end; ++dst)
    {
        *dst = 0U;
    }
    bench_exit(main());
}

typedef void (*vector_t)(void);

__attribute__((section(".isr_vector"), used)) static const vector_t vectors[16] = {
    (vector_t)(uintptr_t)&_stack_top, Reset_Handler, Default_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, 0, 0, 0, 0, Default_Handler, Default_Handler, 0, Default_Handler,
    Default_Handler};
