;;;; tools/fuzz.lisp -- make fuzz: the long random campaigns (#M9W5P7, #SQU33Z).
;;;; SEED (default 1), COUNT sequences (default 1200) and LENGTH operations each (default 150)
;;;; come from the environment; with FUZZ=squeeze it runs the squeeze campaign instead, SCENES
;;;; scenes (default 40) of STEPS steps (default 300).  Prints the figures as Org tables; exit
;;;; status 1 when a sequence broke a promise (its seed and shrunk sequence are printed first)
;;;; or a squeeze left a body outside the air or over its speed bound.  With FUZZ=snapshot it
;;;; damages COUNT (default 2000) copies of each standard scene's snapshot (#SNFUZZ); exit status
;;;; 1 when one left an invalid world or crashed.

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(flet ((setting (name default)
         (let ((text (uiop:getenv name)))
           (if (and text (string/= text "")) (parse-integer text) default)))
       (engine (name) (find-symbol name '#:luv-physics)))
  (let ((seed (setting "SEED" 1)) (start (get-internal-real-time)))
    (flet ((seconds () (/ (- (get-internal-real-time) start) internal-time-units-per-second)))
      (cond
        ((equal (uiop:getenv "FUZZ") "snapshot")
         (let* ((count (setting "COUNT" 2000))
                (rows (funcall (engine "RUN-SNAPSHOT-FUZZ-CAMPAIGN") :seed seed :count count)))
           (format t "make fuzz FUZZ=snapshot SEED=~D COUNT=~D~%~%" seed count)
           (funcall (engine "PRINT-SNAPSHOT-FUZZ-FIGURES") rows (seconds) *standard-output*)
           (finish-output)
           (sb-ext:exit :code (if (every (lambda (row) (and (zerop (getf (cddr row) :invalid))
                                                            (zerop (getf (cddr row) :crashes))))
                                         rows)
                                  0 1))))
        (t
      (if (equal (uiop:getenv "FUZZ") "squeeze")
          (let* ((scenes (setting "SCENES" 40)) (steps (setting "STEPS" 300))
                 (figures (funcall (engine "RUN-SQUEEZE-CAMPAIGN") :seed seed :scenes scenes :steps steps)))
            (format t "make fuzz SEED=~D SCENES=~D STEPS=~D~%~%" seed scenes steps)
            (funcall (engine "PRINT-SQUEEZE-FIGURES") figures (seconds) *standard-output*)
            (finish-output)
            (sb-ext:exit :code (if (and (zerop (getf figures :inside)) (zerop (getf figures :over))) 0 1)))
          (let* ((count (setting "COUNT" 1200)) (length (setting "LENGTH" 150))
                 (figures (funcall (engine "RUN-FUZZ-CAMPAIGN")
                                   :seed seed :sequences count :length length :stream *error-output*)))
            (format t "make fuzz SEED=~D COUNT=~D LENGTH=~D~%~%" seed count length)
            (funcall (engine "PRINT-FUZZ-FIGURES") figures (seconds) *standard-output*)
            (finish-output)
            (sb-ext:exit :code (if (zerop (getf figures :failures)) 0 1)))))))))
